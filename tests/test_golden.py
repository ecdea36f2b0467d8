"""Golden regression: fresh results against tests/golden/ (regenerate with `make golden`).

Structure must match exactly; coefficients may differ by floating-point noise
only (1e-12 of the bounding-box diagonal). A failure lists which patch and
coefficient moved and by how much.
"""
from __future__ import annotations

import copy
import importlib.util
import json
from pathlib import Path

import pytest

_SPEC = importlib.util.spec_from_file_location("golden_regenerate", Path(__file__).parent / "golden" / "regenerate.py")
golden = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(golden)

REGENERATE = "if the change is intended, run `make golden` and commit tests/golden/"


def _load(path: Path) -> dict:
    if not path.exists():
        pytest.fail(f"{path} is missing: run `make golden`", pytrace=False)
    return json.loads(path.read_text(encoding="utf-8"))


@pytest.mark.parametrize("name", golden.GOLDEN_MESHES)
def test_patches_match_golden(name):
    _, doc, _ = golden.build(name)
    old = _load(golden.patch_path(name))
    problems = golden.compare_patch_documents(doc, old)
    assert not problems, f"{name}: the surface changed ({REGENERATE}):\n" + "\n".join(problems)


@pytest.mark.parametrize("name", golden.TESSELLATED)
def test_tessellation_matches_golden(name):
    _, _, tess = golden.build(name)
    old = _load(golden.tessellation_path(name))
    problems = golden.compare_tessellations(tess, old)
    assert not problems, f"{name}: the tessellation changed ({REGENERATE}):\n" + "\n".join(problems)


def test_golden_files_are_what_the_writer_writes():
    """The golden patch file is byte for byte the writer's output (up to the version string)."""
    name = "cube"
    _, doc, _ = golden.build(name)
    old = _load(golden.patch_path(name))
    doc["c1surf_version"] = old["c1surf_version"]
    assert golden.dump(doc) == golden.patch_path(name).read_text(encoding="utf-8")


def test_golden_files_are_small():
    total = sum(p.stat().st_size for p in golden.GOLDEN.glob("*.json"))
    assert total < 4 * 2**20


def test_comparison_separates_noise_from_changes():
    _, doc, _ = golden.build("twisted")
    noisy = copy.deepcopy(doc)
    # floating-point noise: a few ulps on every coefficient
    for patch in noisy["patches"]:
        patch["points"] = [[[x * (1 + 4e-16) for x in p] for p in row] for row in patch["points"]]
    assert golden.compare_patch_documents(noisy, doc) == []
    assert 0 < golden.max_relative_change(noisy, doc) < 1e-14

    # a real change, far below what a viewer would show: 1e-9 of the size
    changed = copy.deepcopy(doc)
    k = 123
    changed["patches"][k]["points"][1][2][0] += 1e-8
    problems = golden.compare_patch_documents(changed, doc)
    assert len(problems) == 1
    kind = doc["patches"][k]["kind"]
    assert problems[0].startswith(f"patch {k} ({kind}, source ")
    assert "points[1][2].x" in problems[0] and "moved 1.000e-08" in problems[0]

    # structural changes are reported by name
    swapped = copy.deepcopy(doc)
    swapped["patches"][5]["edges"][0] += 1
    swapped["options"]["alpha"] = 0.5
    text = "\n".join(golden.compare_patch_documents(swapped, doc))
    assert "header 'options'" in text and "patch 5" in text and "edges" in text
