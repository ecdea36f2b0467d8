"""Hostile patch files (JSON, NPZ, IGES, STEP) for measure, check, tessellate and diff: truncated, wrong
shapes, NaN, absurd degrees, deep nesting, zip bombs, a STEP surface Open CASCADE cannot read. Each: one
``c1surf: error:`` line and no output, or a finite answer; never a traceback, never a silent loss (issue 30)."""
from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings, strategies as st

from hostile_cases import SAMPLES, assert_outcome, run, zip_bomb

pytestmark = pytest.mark.filterwarnings("error")  # a warning would be a second stderr line
FAST = settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
COMMANDS = ["measure", "check", "tessellate", "diff"]


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    """cube.obj's patches in every format c1surf writes (96 patches; IGES and STEP in whole pieces, whose
    entities the cases below edit by their text: the readers take strips and pieces alike)."""
    folder = tmp_path_factory.mktemp("patches")
    paths = {s: folder / f"cube{s}" for s in (".json", ".npz", ".igs", ".step")}
    args = [a for p in paths.values() for a in ("--patches", p)]
    result = run("convert", SAMPLES / "cube.obj", "-o", folder / "cube.ply", "-r", "2", "-q", "--cad-pieces", *args)
    assert result.exit_code == 0, result.output
    return paths


def use(folder, good, command: str, data: bytes, suffix: str, refused: bool | None = None):
    """Run ``command`` on ``data`` saved as bad.SUFFIX (diff: against the good file); assert the promise."""
    source, out = folder / f"bad{suffix}", folder / "out.ply"
    source.write_bytes(data)
    out.unlink(missing_ok=True)
    args = {"measure": [], "check": [], "tessellate": ["-o", out, "-r", "2", "-q"], "diff": []}[command]
    first = [good[suffix], source] if command == "diff" else [source]
    result = run(command, *first, *args)
    assert_outcome(result, folder, [out] if command == "tessellate" else [], verdict=command in ("check", "diff"),
                   must_refuse=bool(refused))
    return result


@pytest.mark.parametrize("suffix", [".json", ".npz", ".igs"])
@FAST
@given(fraction=st.floats(0.0, 1.0, exclude_max=True))
@example(fraction=0.9999999999999999)  # only the last line end cut: the file is whole (found in a fresh-clone run)
def test_truncated(tmp_path, good, suffix, fraction):
    data = good[suffix].read_bytes()
    cut = int(fraction * len(data))
    # refused, unless only trailing white space was cut (an IGES file without its last line end is whole)
    use(tmp_path, good, "measure", data[:cut], suffix, refused=bool(data[cut:].strip()))


@pytest.mark.parametrize("suffix", [".json", ".npz", ".igs", ".step"])
@FAST
@given(data=st.binary(max_size=400))
def test_random_bytes(tmp_path, good, suffix, data):
    use(tmp_path, good, "measure", data, suffix, refused=True)


@pytest.mark.parametrize("cut", [0.0, 0.3, 0.6, 0.99])
def test_truncated_step(tmp_path, good, cut):
    data = good[".step"].read_bytes()
    use(tmp_path, good, "measure", data[: int(cut * len(data))], ".step", refused=True)


def _json_variant(good, change) -> bytes:
    doc = json.loads(good[".json"].read_text())
    change(doc)
    return json.dumps(doc).encode()


def _set(path, value):
    def change(doc):
        target = doc
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value
    return change


JSON_CASES = {
    "points of the wrong shape": _set(["patches", 0, "points"], [[1.0, 2.0]]),
    "points not numbers": _set(["patches", 0, "points"], "abc"),
    "NaN point": _set(["patches", 0, "points", 0, 0, 0], float("nan")),
    "infinite point": _set(["patches", 0, "points", 0, 0, 0], float("inf")),
    "huge point": _set(["patches", 0, "points", 0, 0, 0], 1e308),
    "degree 1e9": _set(["patches", 0, "degree"], [1000000000, 2]),
    "degree -1": _set(["patches", 0, "degree"], [-1, 2]),
    "degree text": _set(["patches", 0, "degree"], ["two", 2]),
    "patches not a list": _set(["patches"], {"a": 1}),
    "a patch not an object": _set(["patches", 0], 5),
    "no format": lambda doc: doc.pop("format"),
    "corner out of range": _set(["patches", 0, "corners"], [10 ** 12, 0, 1, 2]),
    "negative edge": _set(["patches", 0, "edges"], [-5, 0, 1, 2]),
    "nested points": _set(["patches", 0, "points"], [[[[[[1.0]]]]]]),
}


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("case", sorted(JSON_CASES))
def test_json_cases(tmp_path, good, command, case):
    result = use(tmp_path, good, command, _json_variant(good, JSON_CASES[case]), ".json",
                 refused=None if case == "huge point" else True)
    if case != "huge point":
        assert "bad.json" in result.stderr


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("depth", [1000, 100_000])
def test_deep_json_is_one_line(tmp_path, good, command, depth):
    for text in ("[" * depth + "]" * depth, '{"format": "c1surf-patches", "patches": ' + "[" * depth + "]" * depth + "}"):
        result = use(tmp_path, good, command, text.encode(), ".json", refused=True)
        assert "RecursionError" not in result.stderr


def _npz_variant(tmp_path, good, change) -> bytes:
    with np.load(good[".npz"]) as data:
        members = {name: data[name] for name in data.files}
    change(members)
    path = tmp_path / "variant.npz"
    np.savez(path, **members)
    data = path.read_bytes()
    path.unlink()
    return data


def _npz_set(name, value):
    return lambda members: members.__setitem__(name, value)


NPZ_CASES = {
    "wrong shape": _npz_set("biquadratic", np.zeros((4, 3, 3))),
    "NaN": lambda m: m["biquadratic"].__setitem__((0, 0, 0, 0), np.nan),
    "infinity": lambda m: m["bicubic"].__setitem__((1, 1, 1, 1), -np.inf),
    "integers": lambda m: m.__setitem__("biquadratic", m["biquadratic"].astype(np.int64)),
    "no header": lambda m: m.pop("header"),
    "deep header": _npz_set("header", np.array("[" * 100_000 + "]" * 100_000)),
    "header not JSON": _npz_set("header", np.array("{format")),
    "corners out of range": lambda m: m["corners"].__setitem__((0, 0), 10 ** 15),
    "corners of the wrong shape": _npz_set("corners", np.zeros((3,), dtype=np.int64)),
    "source of another length": _npz_set("source", np.zeros((5, 2), dtype=np.int64)),
    "corners as floats with NaN": lambda m: m.__setitem__("corners", np.where(m["corners"] == 0, np.nan, m["corners"])),
    "edges as floats of 1e308": lambda m: m.__setitem__("edges", np.where(m["edges"] == 1, 1e308, m["edges"])),
    "weights of 1e300": lambda m: _weights(m, 1e300, 1.0),
    "weights 1e20 apart": lambda m: _weights(m, 1e10, 1e-10),
}


def _weights(members, high, low):
    """Weights for every patch: ``high`` at the first control point of each, ``low`` elsewhere (issue 42)."""
    for group, n in (("biquadratic", 3), ("bicubic", 4)):
        weights = np.full((len(members[group]), n, n), low)
        weights[:, 0, 0] = high
        members[f"{group}_weights"] = weights


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("case", sorted(NPZ_CASES))
def test_npz_cases(tmp_path, good, command, case):
    use(tmp_path, good, command, _npz_variant(tmp_path, good, NPZ_CASES[case]), ".npz", refused=True)


def test_npz_pickles_are_refused(tmp_path, good):
    def objects(m):
        m["biquadratic"] = np.array([{"a": 1}], dtype=object)
    path = tmp_path / "variant.npz"
    with np.load(good[".npz"]) as data:
        members = {name: data[name] for name in data.files}
    objects(members)
    np.savez(path, **members)
    use(tmp_path, good, "measure", path.read_bytes(), ".npz", refused=True)


@pytest.mark.parametrize("member", ["biquadratic", "header"])
def test_zip_bomb(tmp_path, good, member):
    """A compressed member expanding 64 MB from 64 KB: refused before it is inflated."""
    zip_bomb(tmp_path / "bomb.npz", member, 64 << 20)
    data = (tmp_path / "bomb.npz").read_bytes()
    (tmp_path / "bomb.npz").unlink()
    assert len(data) < 1 << 20
    result = use(tmp_path, good, "measure", data, ".npz", refused=True)
    assert "zip bomb" in result.stderr


IGES_CASES = {
    "degree 1e9": ("128,16,2,2,2,", "128,16,1000000000,2,2,"),
    "degree 0": ("128,16,2,2,2,", "128,16,0,2,2,"),
    "negative count": ("128,16,2,2,2,", "128,-3,2,-3,2,"),
    "count 1e9": ("128,16,2,2,2,", "128,999999999,2,2,2,"),
    "NaN coordinate": ("0.0,0.0,0.0,1.0,2.0,", "nan,0.0,0.0,1.0,2.0,"),
}


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("case", sorted(IGES_CASES))
def test_iges_cases(tmp_path, good, command, case):
    old, new = IGES_CASES[case]
    text = good[".igs"].read_text()
    assert old in text
    use(tmp_path, good, command, text.replace(old, new, 1).encode(), ".igs", refused=True)


@pytest.mark.parametrize("command", COMMANDS)
def test_step_surface_of_degree_1e9_is_named_not_dropped(tmp_path, good, command):
    """The issue's STEP file with one corrupt surface: read as 81 of 96 patches before; now its entity is named."""
    text = good[".step"].read_text()
    match = re.search(r"#(\d+) = B_SPLINE_SURFACE_WITH_KNOTS\('',2,2,", text)
    bad = text.replace(match.group(0), match.group(0).replace("',2,2,", "',1000000000,2,"), 1)
    result = use(tmp_path, good, command, bad.encode(), ".step", refused=True)
    assert f"#{match.group(1)}" in result.stderr


def test_step_with_a_face_entity_removed_from_the_shell_is_refused(tmp_path, good):
    """A face the file declares but no shell holds is still a face the reader did not read."""
    text = good[".step"].read_text()
    faces = re.findall(r"#(\d+) = ADVANCED_FACE", text)
    shell = re.search(r"CLOSED_SHELL\('',\(([^)]*)\)\)", text, re.S)
    ids = [s.strip() for s in shell.group(1).split(",")]
    kept = ",".join(i for i in ids if i != f"#{faces[0]}")
    bad = text.replace(shell.group(0), f"CLOSED_SHELL('',({kept}))", 1)
    result = use(tmp_path, good, "measure", bad.encode(), ".step", refused=True)
    assert "faces" in result.stderr


def test_good_files_still_read(tmp_path, good):
    for suffix, path in good.items():
        shutil.copy(path, tmp_path / f"copy{suffix}")
        result = run("measure", tmp_path / f"copy{suffix}")
        assert result.exit_code == 0 and "patches:   96 (closed)" in result.stdout, (suffix, result.output)
