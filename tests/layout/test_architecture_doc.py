"""docs/architecture.md stays true: its Folders table names every module of c1surf/, and every module (or
function) it names exists where it says; the layer rules it states are the ones pyproject.toml checks."""
from __future__ import annotations

import ast
import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "c1surf"
DOC = ROOT / "docs" / "architecture.md"


def folder_rows() -> dict[str, str]:
    """{folder as written ("mesh/", "construction/refine/", "api.py"): its "what" cell}."""
    text = DOC.read_text()
    table = text[text.index("## Folders"):text.index("## The contract")]
    rows = {}
    for line in table.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 3 and cells[0].startswith("`") and cells[0] != "folder":
            rows[cells[0].strip("`")] = cells[1]
    return rows


def row_for(module: Path, rows: dict) -> str:
    """The row that must name ``module``: its own folder's, else the nearest listed ancestor's."""
    relative = module.relative_to(PACKAGE)
    if len(relative.parts) == 1:
        return relative.name
    for depth in range(len(relative.parts) - 1, 0, -1):
        folder = "/".join(relative.parts[:depth]) + "/"
        if folder in rows:
            return folder
    raise AssertionError(f"no row of docs/architecture.md covers {relative}")


def tokens(cell: str) -> list[str]:
    return re.findall(r"`([^`]+)`", cell)


def test_every_module_is_named_in_its_folder_row():
    rows = folder_rows()
    missing = []
    for module in sorted(PACKAGE.rglob("*.py")):
        if module.name == "__init__.py":
            continue
        row = row_for(module, rows)
        if module.parent == PACKAGE:
            ok = row in rows
        else:
            names = {part for token in tokens(rows[row]) for part in re.split(r"[./:]", token)}
            ok = module.stem in names
        if not ok:
            missing.append(f"{module.relative_to(PACKAGE)} (row {row})")
    assert not missing, "docs/architecture.md does not name: " + ", ".join(missing)


def defined_names(folder: Path) -> set[str]:
    """Module and subpackage stems below ``folder``, and the functions and classes their modules define."""
    names = set()
    for module in folder.rglob("*.py"):
        names.add(module.stem if module.name != "__init__.py" else module.parent.name)
        tree = ast.parse(module.read_text())
        names |= {node.name for node in ast.walk(tree) if isinstance(node, (ast.FunctionDef, ast.ClassDef))}
    return names


def test_every_module_named_exists():
    """A name followed by " (" (the table's "module (what it holds)") is a module, subpackage, function or class
    below the row's folder; a name ending in "/" is a subfolder there."""
    wrong = []
    for folder, cell in folder_rows().items():
        if folder.endswith(".py"):
            assert (PACKAGE / folder).is_file(), folder
            continue
        base = PACKAGE / folder
        assert base.is_dir(), folder
        known = defined_names(base)
        for name in re.findall(r"`([A-Za-z_][A-Za-z0-9_]*)` \(", cell):
            if name not in known:
                wrong.append(f"{folder}: {name}")
        for sub in re.findall(r"`([a-z_]+/)`", cell):
            if not (base / sub).is_dir():
                wrong.append(f"{folder}: {sub}")
    assert not wrong, "docs/architecture.md names what does not exist: " + ", ".join(wrong)


def test_the_layers_it_states_are_the_checked_ones():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]
    layers = next(c for c in config if c["type"] == "layers")["layers"]
    stated = DOC.read_text().split("- layers, top to bottom: ")[1].split(". A")[0]
    named = [part.strip(" `\n") for part in stated.replace("\n", " ").split(",")]
    expected = [" | ".join(m.removeprefix("c1surf.") for m in layer.split(" | ")) for layer in layers]
    assert [n.replace("`", "").strip() for n in named] == expected
