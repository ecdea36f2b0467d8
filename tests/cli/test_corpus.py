"""Every file of ../shared/meshes through `c1surf convert`: a G1 surface or the documented one-line error."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from c1surf.cli.main import main
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.construction.surface import Surface
from c1surf.io.meshes.read import read_mesh

from conftest import SHARED_MESHES

CORPUS = sorted(p.relative_to(SHARED_MESHES).as_posix() for p in SHARED_MESHES.glob("*/*.obj")) if SHARED_MESHES.exists() else []

# The only reasons a corpus file may be refused, each with the files that have it.
REFUSED = {
    "shared by": ["opensubdiv/catmark_fan.obj", "opensubdiv/catmark_nonman_edge100.obj", "opensubdiv/catmark_val2_nonman.obj"],
    "interior vertex of valence 2": [
        "opensubdiv/catmark_gregory_test8.obj",
        "opensubdiv/catmark_val2_back2back.obj",
        "opensubdiv/catmark_val2_foldover.obj",
        "opensubdiv/catmark_val2_interior.obj",
    ],
    "fewer than 3 distinct vertices": ["opensubdiv/catmark_nonman_edges.obj"],
}
EXPECTED_ERROR = {name: reason for reason, names in REFUSED.items() for name in names}
OUTCOMES: dict[str, str] = {}


@pytest.mark.skipif(not CORPUS, reason="../shared/meshes not available")
@pytest.mark.parametrize("relative", CORPUS)
def test_corpus_file(relative, tmp_path):
    path = SHARED_MESHES / relative
    out = tmp_path / "out.ply"
    result = CliRunner().invoke(main, ["convert", str(path), "-o", str(out), "--resolution", "2", "--quiet"])
    stderr = result.stderr.strip().splitlines()
    if relative in EXPECTED_ERROR:
        assert result.exit_code == 1, result.output
        assert len(stderr) == 1 and stderr[0].startswith(f"c1surf: error: {path}:")
        assert EXPECTED_ERROR[relative] in stderr[0]
        assert not out.exists()
        OUTCOMES[relative] = "refused: " + EXPECTED_ERROR[relative]
        return
    assert result.exit_code == 0, result.output
    mesh = trimesh.load(out, force="mesh", process=False)
    assert np.isfinite(mesh.vertices).all() and len(mesh.faces) > 0
    data = read_mesh(path)
    surface = Surface(data.face_sizes, data.face_vertices, data.points)
    report = measure_smoothness([surface.biquadratic, surface.bicubic])
    assert report.overshared_edges == 0 and report.relative_gap < 1e-12
    # `c1surf check`'s tolerance. Measured worst: 1.2e-10 rad on catmark_bishop, round-off at its
    # 24-valent pole (6e-12 with the pole moved to the origin, 1.5e-9 moved 100 units away).
    assert report.max_normal_jump < 1e-9, report
    OUTCOMES[relative] = f"converted: {surface.n_patches} patches, max normal jump {report.max_normal_jump:.1e} rad" + (
        f", {report.boundary_edges} boundary patch edges" if report.boundary_edges else ""
    )


@pytest.mark.skipif(not CORPUS, reason="../shared/meshes not available")
def test_corpus_outcome_table(capsys):
    """Print the table (run with -s to see it); every file has exactly one outcome."""
    with capsys.disabled():
        converted = sum(v.startswith("converted") for v in OUTCOMES.values())
        print(f"\ncorpus: {len(OUTCOMES)} files, {converted} converted, {len(OUTCOMES) - converted} refused")
        for name in sorted(OUTCOMES):
            print(f"  {name:60s} {OUTCOMES[name]}")
    if len(OUTCOMES) == len(CORPUS):
        assert converted == len(CORPUS) - len(EXPECTED_ERROR)
