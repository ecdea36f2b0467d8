"""``c1surf fit --cage``: the fitted control mesh as an OBJ cage that ``c1surf convert`` turns into the fitted
surface bit for bit (issue 34): every array of the patch file equal with ==, the tessellation byte for byte."""
from __future__ import annotations

import json
import shlex
from pathlib import Path

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from c1surf.cli.main import main
from c1surf.construction.features import SharpFeatures
from c1surf.io.meshes.obj_out import write_cage
from c1surf.io.meshes.read import read_mesh

SCANS = Path(__file__).resolve().parents[2].parent / "shared" / "scans"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def convert_command(cage: Path) -> list:
    """The ``convert`` options the cage's first line names (``c1surf convert NAME FLAGS gives ...``)."""
    first = cage.read_text().splitlines()[0]
    assert first.startswith("# c1surf fit cage:"), first
    words = shlex.split(first.split("c1surf convert ", 1)[1].split(" gives ")[0])
    assert words[0] == cage.name
    return words[1:]


def fit_and_convert(scan, folder: Path, *fit_options, flags=None):
    """Fit ``scan`` writing the cage, a patch file and a tessellation; convert the cage the same way. Returns the
    NPZ archives (fit, convert), the two PLY files' bytes and the convert flags used."""
    cage = folder / "cage.obj"
    result = run("fit", scan, "--iterations", 3, "-r", 4, "--cage", cage, "--patches", folder / "fit.npz",
                 "-o", folder / "fit.ply", "--report", folder / "fit.json", *fit_options)
    assert result.exit_code == 0, result.output
    assert "--cage" not in result.stderr  # no note: the fit checked the cage rebuilds it
    # a closed scan of one piece, kept: the summary's line and the report's counts side by side
    assert "topology:         1 component, Euler characteristic 2, 0 rims (the scan's)" in result.stdout
    topology = json.loads((folder / "fit.json").read_text())["topology"]
    assert topology["scan"]["euler_characteristic"] == topology["surface"]["euler_characteristic"] == 2
    assert topology["differences"] == []
    flags = convert_command(cage) if flags is None else flags
    result = run("convert", cage, "-r", 4, "-o", folder / "convert.ply", "--patches", folder / "convert.npz", *flags)
    assert result.exit_code == 0, result.output
    return (np.load(folder / "fit.npz"), np.load(folder / "convert.npz"),
            (folder / "fit.ply").read_bytes(), (folder / "convert.ply").read_bytes(), flags)


def assert_same_patches(fitted, converted):
    assert sorted(fitted.files) == sorted(converted.files)
    for key in fitted.files:
        if key != "header":  # the header names the source file
            assert fitted[key].dtype == converted[key].dtype and np.array_equal(fitted[key], converted[key]), key
    assert fitted["biquadratic"].size + fitted["bicubic"].size > 0


@pytest.fixture(scope="module")
def ellipsoid_scan(tmp_path_factory):
    """A synthetic scan: an icosphere of 1,280 triangles stretched into an ellipsoid and bent."""
    sphere = trimesh.creation.icosphere(subdivisions=3)
    points = sphere.vertices * [2.0, 1.0, 0.7]
    points[:, 2] += 0.3 * points[:, 0] ** 2
    path = tmp_path_factory.mktemp("scan") / "ellipsoid.obj"
    trimesh.Trimesh(points, sphere.faces, process=False).export(path)
    return path


def test_the_cage_converts_to_the_fitted_surface_bit_for_bit(ellipsoid_scan, tmp_path):
    fitted, converted, fit_ply, convert_ply, flags = fit_and_convert(ellipsoid_scan, tmp_path, "--faces", 60)
    assert flags[:1] == ["--refinements"]
    assert_same_patches(fitted, converted)
    assert fit_ply == convert_ply
    # refinements "auto" (fit's default) chooses the same steps from the same cage
    again = tmp_path / "auto"
    again.mkdir()
    result = run("convert", tmp_path / "cage.obj", "-o", again / "c.ply", "-r", 4, "--patches", again / "c.npz",
                 "--refinements", "auto")
    assert result.exit_code == 0, result.output
    assert_same_patches(fitted, np.load(again / "c.npz"))


def test_the_cage_is_the_fitted_control_mesh_with_its_creases(tmp_path):
    """wingnut with --crease-angle: the cage carries the crease tags; since issue 35 the fit's feature lines are C0
    up to their darts and crease sectors are merged as convert merges them, so convert's default creases rebuild the
    fit (no ``--g1-creases``); ``--g1-creases`` builds another surface: the tags matter."""
    fitted, converted, fit_ply, convert_ply, flags = fit_and_convert(
        SCANS / "wingnut.obj", tmp_path, "--faces", 150, "--crease-angle", 45)
    assert "--g1-creases" not in flags
    assert_same_patches(fitted, converted)
    assert fit_ply == convert_ply
    cage = read_mesh(tmp_path / "cage.obj")
    assert cage.tags is not None and len(cage.tags.crease_edges) > 20
    assert np.all(cage.tags.crease_sharpness == 10.0)
    result = run("convert", tmp_path / "cage.obj", "-r", 4, "-o", tmp_path / "d.ply", "--patches", tmp_path / "d.npz",
                 *flags, "--g1-creases")
    assert result.exit_code == 0
    other = np.load(tmp_path / "d.npz")
    assert other["biquadratic"].shape != fitted["biquadratic"].shape or \
        not np.array_equal(other["biquadratic"], fitted["biquadratic"])


def cylinder_scan(folder: Path, sections: int, subdivisions: int) -> Path:
    mesh = trimesh.creation.cylinder(radius=1.0, height=1.5, sections=sections)
    for _ in range(subdivisions):
        mesh = mesh.subdivide()
    path = folder / "cylinder.obj"
    mesh.export(path)
    return path


def test_a_cage_with_c0_creases_converts_to_the_fitted_surface_bit_for_bit(tmp_path):
    """A cylinder with --crease-angle 45: its two rims are closed crease loops, C0 seams, and since issue 40 one
    Doo-Sabin step (R1-R3 hold on the cells the kept patches read: the sheets' ghost quads close the cut)."""
    fitted, converted, fit_ply, convert_ply, flags = fit_and_convert(cylinder_scan(tmp_path, 32, 1), tmp_path,
                                                                      "--faces", 80, "--crease-angle", 45)
    assert flags == ["--refinements", "1"]  # C0 seams: convert's default creases
    assert_same_patches(fitted, converted)
    assert fit_ply == convert_ply
    edges = read_mesh(tmp_path / "cage.obj").tags.crease_edges
    assert len(edges) >= 16 and np.all(np.bincount(edges.ravel())[np.unique(edges)] == 2)  # closed loops


def test_a_cage_with_a_crease_sector_converts_bit_for_bit(tmp_path):
    """The same cylinder cut finer: the remesh has a crease sector of three faces. Before issue 35 the fit kept it
    and convert's preparation merged it (1,720 patches against the fit's 1,728, a note and a cage line said so);
    now the fit merges crease sectors as convert does, and the cage rebuilds the fit bit for bit."""
    fitted, converted, fit_ply, convert_ply, flags = fit_and_convert(cylinder_scan(tmp_path, 32, 2), tmp_path,
                                                                      "--faces", 100, "--crease-angle", 45)
    assert "--g1-creases" not in flags
    assert_same_patches(fitted, converted)
    assert fit_ply == convert_ply


def test_write_cage_round_trips_every_bit_and_every_tag(tmp_path):
    rng = np.random.default_rng(5)
    points = rng.normal(size=(8, 3)) * 10.0 ** rng.integers(-12, 12, size=(8, 3))
    points[0] = [1 / 3, -0.0, 5e-324]
    points[1] = [1e300, -2.0 ** -1074, 0.1]
    sizes = np.array([4, 3, 5])
    corners = np.array([0, 1, 2, 3, 3, 2, 4, 4, 2, 5, 6, 7])
    features = SharpFeatures(crease_edges=[[0, 1], [2, 3]], crease_sharpness=[10.0, 2.0 / 3.0],
                             corner_vertices=[7], corner_sharpness=[1.25], hole_faces=[1])
    path = tmp_path / "cage.obj"
    write_cage(path, points, sizes, corners, features, ["one", "two"])
    mesh = read_mesh(path)
    assert np.array_equal(np.asarray(mesh.points)[:, :3].view(np.int64), points.view(np.int64))  # -0.0 too
    assert np.array_equal(mesh.face_sizes, sizes) and np.array_equal(mesh.face_vertices, corners)
    tags = mesh.tags
    assert np.array_equal(tags.crease_edges, features.crease_edges)
    assert np.array_equal(tags.crease_sharpness, features.crease_sharpness)
    assert np.array_equal(tags.corner_vertices, [7]) and np.array_equal(tags.corner_sharpness, [1.25])
    assert np.array_equal(tags.hole_faces, [1])
    assert path.read_text().startswith("# one\n# two\nv ")


def test_a_cage_that_does_not_rebuild_the_fit_is_named_in_a_note(ellipsoid_scan, tmp_path, monkeypatch):
    import dataclasses

    import c1surf.api as api

    real = api.cage_options

    def wrong(surface):
        options, inputs = real(surface)
        return dataclasses.replace(options, blend=0.3), inputs

    monkeypatch.setattr(api, "cage_options", wrong)
    surface, report = api.fit_surface(ellipsoid_scan, api_options(), api.SurfaceOptions(refinements="auto"))
    notes = api.write_fit_cage(tmp_path / "c.obj", surface, report, ["c1surf fit cage: ... bit for bit", "tags"])
    assert len(notes) == 1 and "builds a different surface" in notes[0]
    first, second = (tmp_path / "c.obj").read_text().splitlines()[:2]
    assert first.startswith("# c1surf fit cage: the fitted control mesh; convert does NOT rebuild") and second == "# tags"


def api_options():
    from c1surf.fitting.options import FitOptions
    from c1surf.fitting.scan_fit import ScanFitOptions

    return ScanFitOptions(faces=60, fit=FitOptions(max_iterations=2))


def test_a_cage_that_is_not_obj_is_one_line(ellipsoid_scan, tmp_path):
    result = run("fit", ellipsoid_scan, "--faces", 60, "--cage", tmp_path / "cage.ply")
    lines = result.stderr.strip().splitlines()
    assert result.exit_code != 0 and len(lines) == 1 and lines[0].startswith("c1surf: error: ") and "--cage" in lines[0]
    assert not (tmp_path / "cage.ply").exists()


def test_the_cage_never_overwrites_the_control_mesh_it_was_fitted_with(ellipsoid_scan, tmp_path):
    first = tmp_path / "first.obj"
    assert run("fit", ellipsoid_scan, "--faces", 60, "--iterations", 1, "--cage", first).exit_code == 0
    before = first.read_bytes()
    result = run("fit", ellipsoid_scan, "--control-mesh", first, "--iterations", 1, "--cage", first)
    lines = result.stderr.strip().splitlines()
    assert result.exit_code != 0 and lines[-1].startswith("c1surf: error: ") and first.read_bytes() == before
    second = tmp_path / "second.obj"  # fitted again from its own cage: the same connectivity
    assert run("fit", ellipsoid_scan, "--control-mesh", first, "--iterations", 1, "--cage", second).exit_code == 0
    assert [line for line in second.read_text().splitlines() if line.startswith("f ")] == \
        [line for line in before.decode().splitlines() if line.startswith("f ")]


def test_an_open_scan_fits_at_one_step_and_its_cage_converts_bit_for_bit(tmp_path):
    """An open scan (a bent ellipsoid with its top cut off, one rim): since issue 40 the fit takes one Doo-Sabin
    step on the open control mesh (four patches a face), and its cage rebuilds the fit bit for bit."""
    sphere = trimesh.creation.icosphere(subdivisions=3)
    keep = sphere.vertices[sphere.faces].max(axis=1)[:, 2] < 0.6
    points = sphere.vertices * [2.0, 1.0, 0.7]
    points[:, 2] += 0.3 * points[:, 0] ** 2
    scan = tmp_path / "bowl.obj"
    trimesh.Trimesh(points, sphere.faces[keep], process=False).export(scan)
    cage = tmp_path / "cage.obj"
    result = run("fit", scan, "--faces", 60, "--iterations", 3, "--cage", cage, "--patches", tmp_path / "fit.npz",
                 "--report", tmp_path / "fit.json")
    assert result.exit_code == 0, result.output
    assert "--cage" not in result.stderr
    report = json.loads((tmp_path / "fit.json").read_text())
    assert report["topology"]["surface"]["rims"] == 1 and report["patches"]["refinements"] == 1
    control = report["control_mesh"]["faces"]
    assert report["patches"]["total"] <= 5 * control
    flags = convert_command(cage)
    assert flags == ["--refinements", "1"]
    result = run("convert", cage, "-o", tmp_path / "c.ply", "--patches", tmp_path / "convert.npz", *flags)
    assert result.exit_code == 0, result.output
    assert_same_patches(np.load(tmp_path / "fit.npz"), np.load(tmp_path / "convert.npz"))
