"""The README stays short and every relative link of the documentation leads somewhere.

- README.md has at most 320 lines (the rest lives in ``docs/``, one page per topic);
- every relative link or image in README.md and docs/*.md names an existing file, and a
  ``#anchor`` names a heading of the page it points to (GitHub's anchors: lower case,
  punctuation dropped, spaces as hyphens, ``-1``, ``-2`` for repeats).
"""
from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
MAX_README_LINES = 320
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(([^()\s]+)(?:\s+\"[^\"]*\")?\)")


def prose_lines(text: str) -> list[str]:
    """The lines of a Markdown text outside fenced code blocks, inline code spans removed."""
    lines, fenced = [], False
    for line in text.splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if not fenced:
            lines.append(re.sub(r"`[^`]*`", "", line))
    return lines


def slug(heading: str) -> str:
    """GitHub's anchor of a heading's text."""
    text = heading.strip().lower().replace("`", "")
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def anchors(path: Path) -> set[str]:
    """Every heading anchor of a Markdown page, repeats numbered as GitHub numbers them."""
    seen: dict[str, int] = {}
    found = set()
    text, fenced = path.read_text(encoding="utf-8"), False
    for line in text.splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
        elif not fenced and (match := re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)):
            base = slug(match.group(1))
            count = seen.get(base, 0)
            found.add(base if count == 0 else f"{base}-{count}")
            seen[base] = count + 1
    return found


def links(path: Path) -> list[str]:
    """The relative link targets of a page (web and mail addresses left out)."""
    targets = []
    for line in prose_lines(path.read_text(encoding="utf-8")):
        targets += [t for t in LINK.findall(line) if not re.match(r"[a-z][a-z0-9+.-]*:", t)]
    return targets


def broken(path: Path) -> list[str]:
    """The links of a page whose file does not exist or whose anchor names no heading there."""
    bad = []
    for target in links(path):
        file, _, anchor = target.partition("#")
        destination = (path.parent / file).resolve() if file else path
        if not destination.exists():
            bad.append(f"{target}: no such file")
        elif anchor and destination.suffix == ".md" and anchor not in anchors(destination):
            bad.append(f"{target}: no such heading in {destination.name}")
    return bad


def test_readme_fits_on_a_few_screens():
    lines = len((ROOT / "README.md").read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_README_LINES, f"README.md has {lines} lines: move sections to docs/"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_leads_somewhere(page):
    assert not broken(page)


def test_the_readme_links_every_topic_page():
    targets = {t.partition("#")[0] for t in links(ROOT / "README.md")}
    for name in ["cli", "python", "sharp-features", "tessellation", "rendering", "cad-exchange", "performance",
                 "paper-notes", "fit"]:
        assert f"docs/{name}.md" in targets, name


def test_the_link_check_sees_a_broken_link_and_a_missing_anchor(tmp_path):
    (tmp_path / "other.md").write_text("# A title: `with code`\n\n## Twice\n\n## Twice\n")
    page = tmp_path / "page.md"
    page.write_text("[ok](other.md#a-title-with-code) [ok](other.md#twice-1) ![x](missing.png)\n"
                    "[bad](other.md#nowhere) `[code](missing.md)` [web](https://example.org/x)\n"
                    "```\n[fenced](missing.md)\n```\n")
    assert broken(page) == ["missing.png: no such file", "other.md#nowhere: no such heading in other.md"]
