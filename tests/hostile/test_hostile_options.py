"""Every numeric option of every command, given NaN, infinity, negative, huge and non-numbers: a one-line usage
error (exit 2) or a finite output; and click's own usage errors as one line (issue 30)."""
from __future__ import annotations

import shutil

import pytest

from hostile_cases import SAMPLES, assert_batch_outcome, assert_outcome, run

pytestmark = pytest.mark.filterwarnings("error")  # a warning would be a second stderr line

NOT_FINITE = ["nan", "inf", "-inf", "NaN", "+Infinity"]
OTHER = ["-1", "0", "1e308", "-1e308", "1e-320", "abc", ""]

# command, option, how many numbers it takes
FLOAT_OPTIONS = [
    ("convert", "--blend", 1), ("convert", "--alpha", 1), ("convert", "--beta", 1), ("convert", "--weld", 1),
    ("convert", "--crease-angle", 1), ("convert", "--tolerance", 1),
    ("check", "--tolerance", 1), ("check", "--blend", 1), ("check", "--weld", 1),
    ("diff", "--tolerance", 1), ("tessellate", "--tolerance", 1), ("batch", "--blend", 1), ("batch", "--beta", 1),
    ("render", "--fov", 1), ("render", "--zoom", 1), ("render", "--eye", 3), ("render", "--target", 3),
    ("render", "--up", 3), ("render", "--range", 2), ("render", "--stripe-axis", 3),
]
INT_OPTIONS = [("convert", "-r"), ("check", "--samples"), ("tessellate", "-r"), ("inspect", "-r"), ("batch", "-j"),
               ("batch", "-r"), ("render", "--tile"), ("render", "--stripes"), ("render", "--mesh-resolution")]


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    folder = tmp_path_factory.mktemp("options")
    shutil.copy(SAMPLES / "cube.obj", folder / "cube.obj")
    result = run("convert", folder / "cube.obj", "-o", folder / "cube.ply", "-r", "2", "--patches", folder / "cube.json")
    assert result.exit_code == 0, result.output
    return folder


def command_line(command: str, folder, option: str, values: list):
    """The arguments of ``command`` on the cube with ``option values``, and the outputs it would write."""
    out = folder / "out.ply"
    heads = {"convert": (["convert", folder / "cube.obj", "-o", out, "-r", "2", "-q"], [out]),
             "check": (["check", folder / "cube.obj"], []),
             "diff": (["diff", folder / "cube.json", folder / "cube.json"], []),
             "tessellate": (["tessellate", folder / "cube.json", "-o", out, "-q"], [out]),
             "inspect": (["inspect", folder / "cube.obj"], []),
             "batch": (["batch", str(folder / "cube.obj"), "-o", folder / "batch", "-q"], [folder / "batch" / "cube.ply"]),
             "render": (["render", folder / "cube.json", "-o", folder / "out.exr", "--size", "8"], [folder / "out.exr"])}
    args, outputs = heads[command]
    return [*args, option, *values], outputs


@pytest.mark.parametrize("value", NOT_FINITE)
@pytest.mark.parametrize("command,option,count", FLOAT_OPTIONS)
def test_non_finite_floats_are_usage_errors(workspace, command, option, count, value):
    args, outputs = command_line(command, workspace, option, ["1"] * (count - 1) + [value])
    result = run(*args)
    assert_outcome(result, workspace, outputs, refused_status=(2,), must_refuse=True)
    assert option in result.stderr or "--tolerance" in result.stderr


@pytest.mark.parametrize("value", OTHER)
@pytest.mark.parametrize("command,option,count", [o for o in FLOAT_OPTIONS if o[0] not in ("render", "batch")])
def test_other_floats_are_refused_or_give_finite_output(workspace, command, option, count, value):
    args, outputs = command_line(command, workspace, option, ["1"] * (count - 1) + [value])
    assert_outcome(run(*args), workspace, outputs, verdict=command in ("check", "diff"))
    shutil.rmtree(workspace / "batch", ignore_errors=True)
    for output in outputs:
        output.unlink(missing_ok=True)


@pytest.mark.parametrize("value", ["nan", "-1", "0", "1.5", "10000000000000000000000", "abc"])
@pytest.mark.parametrize("command,option", INT_OPTIONS)
def test_integer_options(workspace, command, option, value):
    args, outputs = command_line(command, workspace, option, [value])
    result = run(*args)
    if command == "batch":  # its summary, then one line per file it could not convert
        assert_batch_outcome(result, workspace / "cube.obj", outputs[0])
        refused = result.exit_code != 0
    else:
        refused = assert_outcome(result, workspace, outputs, verdict=command in ("check", "diff"))
    if value in ("nan", "1.5", "abc", "-1"):
        assert refused and result.exit_code == 2
    shutil.rmtree(workspace / "batch", ignore_errors=True)
    for output in outputs:
        output.unlink(missing_ok=True)


def test_the_issue_cases(workspace):
    """`convert --blend nan` (also --alpha, --beta nan/inf), `diff --tolerance nan`, `check --tolerance nan`,
    `--weld nan`, `--crease-angle nan`: refused in one line each, exit 2, nothing written."""
    out = workspace / "x.ply"
    for option, value in [("--blend", "nan"), ("--alpha", "nan"), ("--beta", "nan"), ("--beta", "inf"),
                          ("--weld", "nan"), ("--crease-angle", "nan")]:
        result = run("convert", workspace / "cube.obj", "-o", out, option, value)
        assert_outcome(result, workspace, [out], refused_status=(2,), must_refuse=True)
        assert result.stderr.strip() == (f"c1surf: error: {option}: {value} is not a finite number "
                                         "(see `main convert --help`)")
    result = run("diff", workspace / "cube.json", workspace / "cube.json", "--tolerance", "nan")
    assert_outcome(result, workspace, refused_status=(2,), must_refuse=True)
    result = run("check", workspace / "cube.json", "--tolerance", "nan")
    assert_outcome(result, workspace, refused_status=(2,), must_refuse=True)


def test_out_of_range_in_interval_words(workspace):
    out = workspace / "x.ply"
    result = run("convert", workspace / "cube.obj", "-o", out, "--blend", "2")
    assert result.exit_code == 2
    assert result.stderr.strip() == "c1surf: error: --blend: 2 is not in [0, 1] (see `main convert --help`)"
    result = run("convert", workspace / "cube.obj", "-o", out, "--crease-angle", "180")
    assert result.stderr.strip().startswith("c1surf: error: --crease-angle: 180 is not in [0, 180)")


@pytest.mark.parametrize("args", [
    ["convert"], ["convert", "cube.obj"], ["convert", "cube.obj", "-o"], ["convert", "cube.obj", "-o", "x.ply", "--blned", "1"],
    ["convert", "cube.obj", "-o", "x.ply", "extra"], ["frobnicate"], ["convert", "cube.obj", "-o", "x.ply", "--refinements", "7"],
    ["diff", "a.json"], ["render", "cube.obj", "-o", "x.png", "--view", "nowhere"], ["batch"], ["--nonsense"],
])
def test_click_usage_errors_are_one_line(workspace, args, monkeypatch):
    monkeypatch.chdir(workspace)
    result = run(*args)
    assert_outcome(result, workspace, [workspace / "x.ply"], refused_status=(2,), must_refuse=True)
    assert "Usage:" not in result.stderr and "Try " not in result.stderr
    assert result.stderr.rstrip().endswith("--help`)")


SIDECARS = [
    ("--blend-file", '{"default": NaN}'), ("--blend-file", '{"default": 0.5, "faces": {"0": Infinity}}'),
    ("--blend-file", '{"default": -1}'), ("--blend-file", "[" * 50_000 + "]" * 50_000), ("--blend-file", "{"),
    ("--creases", '{"creases": [[0, 1, NaN]]}'), ("--creases", '{"creases": [[0, 1, 1e400]]}'),
    ("--creases", '{"corners": [[0, -5]]}'), ("--creases", '{"creases": [[0, 99999999999, 10]]}'),
    ("--creases", "[" * 50_000 + "]" * 50_000), ("--creases", '{"holes": [1e20]}'),
]


@pytest.mark.parametrize("option,text", SIDECARS)
def test_sidecar_json_numbers(workspace, option, text):
    """The JSON files options name (--blend-file, --creases): NaN, infinities, out-of-range values, nesting."""
    sidecar = workspace / "sidecar.json"
    sidecar.write_text(text)
    out = workspace / "out.ply"
    result = run("convert", workspace / "cube.obj", "-o", out, "-r", "2", "-q", option, sidecar)
    assert_outcome(result, workspace, [out], must_refuse=True)
    assert "sidecar.json" in result.stderr
    sidecar.unlink()
