"""One road from a file to a Surface, options as objects (issue 28).

- no function has more than 8 parameters, no click command more than 12: options travel grouped
  (SurfaceOptions, InputOptions, PatchFileOptions, CameraPlacement, ...), not as loose keywords;
- the input preparation (``c1surf.prepare``) is used by ``c1surf.api`` alone (import-linter checks that cli, io and
  render do not import it; this checks the same from the source, and that ``api.load_surface`` is what the commands
  call to build a surface from a mesh file).
"""
from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from c1surf.api import InputOptions, SurfaceOptions, load_surface, surface_from_file
from c1surf.errors import OptionError

from conftest import SAMPLES

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "c1surf"


def functions():
    for module in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(module.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                yield module.relative_to(ROOT), node


def parameter_count(node) -> int:
    a = node.args
    names = [x.arg for x in a.posonlyargs + a.args]
    n = len(names) + len(a.kwonlyargs) + (a.vararg is not None) + (a.kwarg is not None)
    return n - (1 if names and names[0] in ("self", "cls") else 0)


def is_click_command(node) -> bool:
    return any("click.command" in ast.unparse(d) for d in node.decorator_list)


def test_no_function_takes_more_than_eight_parameters_and_no_command_more_than_twelve():
    too_many = [f"{path}:{node.lineno} {node.name} ({parameter_count(node)})" for path, node in functions()
                if parameter_count(node) > (12 if is_click_command(node) else 8)]
    assert not too_many, "group the options into an object: " + ", ".join(too_many)


def imports_of(path: Path) -> set[str]:
    """The modules ``path`` imports, as absolute dotted names."""
    package = ".".join(path.relative_to(ROOT).with_suffix("").parts[:-1])
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            base = package.rsplit(".", node.level - 1)[0] if node.level else ""
            found.add(f"{base}.{node.module}" if base and node.module else (node.module or base))
        elif isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
    return found


def test_only_the_api_prepares_a_mesh_file():
    users = sorted(str(p.relative_to(ROOT)) for p in PACKAGE.rglob("*.py")
                   if not p.is_relative_to(PACKAGE / "prepare")
                   and any(name.startswith("c1surf.prepare") for name in imports_of(p)))
    assert users == ["c1surf/api.py"]


def test_every_command_that_builds_a_surface_goes_through_the_api():
    """The commands read mesh files only through ``c1surf.api`` (``inspect`` and ``diff`` read a mesh for counts
    and vertices too, which is the reader's job and prepares nothing)."""
    for name in ("convert", "check", "render", "reports/measure", "reports/inspect", "batch"):
        source = (PACKAGE / "cli" / f"{name}.py").read_text()
        assert not re.search(r"(?<![A-Za-z_.])Surface\(", source), name  # no construction outside the api
    for name in ("convert", "check", "render", "reports/inspect"):
        assert "c1surf.api" in imports_of(PACKAGE / "cli" / f"{name}.py"), name


def test_load_surface_is_surface_from_file():
    surface, report = load_surface(SAMPLES / "twisted.obj", SurfaceOptions(blend=0.3), InputOptions(crease_angle=40))
    same, mesh = surface_from_file(SAMPLES / "twisted.obj", blend=0.3, crease_angle=40)
    assert (surface.bicubic == same.bicubic).all() and (surface.biquadratic == same.biquadratic).all()
    assert report.mesh.n_faces == mesh.n_faces and any("--crease-angle 40" in note for note in report.notes)
    assert surface.options.exact_creases  # the one default: C0 creases unless vertices are interpolated
    interpolated, _ = load_surface(SAMPLES / "cube.obj", SurfaceOptions(interpolate_vertices=True))
    assert not interpolated.options.exact_creases


def test_contradicting_options_are_one_option_error():
    with pytest.raises(OptionError, match="beta"):
        load_surface(SAMPLES / "cube.obj", SurfaceOptions(beta=0.5), InputOptions(normals=True))
    with pytest.raises(OptionError, match="weld"):
        load_surface(SAMPLES / "cube.obj", input_options=InputOptions(weld=float("nan")))
    with pytest.raises(TypeError, match="unknown options"):
        surface_from_file(SAMPLES / "cube.obj", blnd=0.3)
