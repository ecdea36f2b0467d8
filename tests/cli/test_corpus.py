"""Every file of ../shared/meshes through `c1surf convert`: a G1 surface or the documented one-line error."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from c1surf.api import surface_from_file
from c1surf.cli.main import main
from c1surf.evaluation.smoothness import measure_smoothness

from conftest import SHARED_MESHES

CORPUS = sorted(p.relative_to(SHARED_MESHES).as_posix() for p in SHARED_MESHES.glob("*/*.obj")) if SHARED_MESHES.exists() else []

# The only reasons a corpus file may be refused, each with the files that have it.
REFUSED = {
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
    surface, _ = surface_from_file(path)  # the surface convert built: tags honoured, welded, valence 2 dissolved
    # G1 across every shared side but the C0 crease pieces, which must meet (non-manifold edges: sheets)
    report = measure_smoothness([surface.biquadratic, surface.bicubic], crease_sides=surface.crease_sides)
    assert report.overshared_edges == 0 and report.relative_gap < 1e-12
    assert report.unpaired_crease_sides == 0 and report.relative_crease_gap < 1e-12
    # Measured worst: 4.9e-11 rad on catmark_bishop with its creases (round-off at its 24-valent pole
    # and thin creased cells; 1.4e-10 untagged before the stages ran on centred points).
    assert report.max_normal_jump < 1e-10, report
    OUTCOMES[relative] = f"converted: {surface.n_patches} patches, max normal jump {report.max_normal_jump:.1e} rad" + (
        f", {report.boundary_edges} boundary patch edges" if report.boundary_edges else "") + (
        f", {report.crease_edges} C0 crease pieces, gap {report.relative_crease_gap:.0e}" if report.crease_edges else "")


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
