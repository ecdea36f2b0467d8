"""evaluation.stream.StreamedSurface: what a streamed conversion keeps of a Surface, and that the rest goes."""
from __future__ import annotations

import gc
import weakref
from pathlib import Path

import numpy as np
import pytest

from c1surf.construction.surface import Surface
from c1surf.evaluation.patch_set import surface_patch_stream
from c1surf.evaluation.stream import StreamedSurface
from c1surf.evaluation.tessellate import patch_adjacency
from c1surf.io.meshes.read import read_mesh

ROOT = Path(__file__).resolve().parents[2]


def _surface(name: str, **kwargs) -> Surface:
    m = read_mesh(ROOT / "sample_meshes" / f"{name}.obj")
    return Surface(m.face_sizes, m.face_vertices, m.points, lazy_patches=True, **kwargs)


@pytest.mark.parametrize("name", ["twisted", "high_valence", "cube"])
def test_the_kept_parts_are_the_surfaces(name):
    surface = _surface(name)
    kept = StreamedSurface(surface, sources=True)
    expected = surface_patch_stream(surface, "in.obj")
    assert kept.adjacency == patch_adjacency(surface.refined, surface.frames) == expected.adjacency
    assert kept.counts == expected.counts and kept.n_patches == surface.n_patches
    got = kept.patch_stream("in.obj")
    assert got.header == expected.header
    assert np.array_equal(got.source_kind, expected.source_kind)
    for name_, _, dtype in got.INTEGERS:
        a, b = got.integers(name_, 0, got.n_patches), expected.integers(name_, 0, got.n_patches)
        assert a.dtype == b.dtype == np.dtype(dtype) and np.array_equal(a, b), name_
    eager = _surface(name)
    for whole, arrays in zip(kept.whole_patches(), (eager.biquadratic, eager.bicubic)):
        assert np.array_equal(whole, arrays)
    assert surface._patches is None  # the whole arrays came from the source, not the Surface


def test_the_build_goes_once_the_surface_is_dropped():
    """The stages go with the Surface; the topology (refined meshes) once the adjacency is made; only the
    patch source's layouts and refined points, the adjacency and the sources stay."""
    surface = _surface("twisted")
    stage, topology = weakref.ref(surface.stages[1]), weakref.ref(surface.topology)
    kept = StreamedSurface(surface, sources=True)
    del surface
    gc.collect()
    assert stage() is None and topology() is not None
    kept.adjacency
    gc.collect()
    assert topology() is None
    assert kept.patch_stream().n_patches == kept.n_patches


def test_a_stream_without_sources_refuses_patch_files_and_rational_surfaces_are_refused():
    kept = StreamedSurface(_surface("cube"))
    with pytest.raises(ValueError, match="without the patches' sources"):
        kept.patch_stream()
    m = read_mesh(ROOT / "sample_meshes" / "cube.obj")
    rational = Surface(m.face_sizes, m.face_vertices, m.points, weights=np.linspace(1, 2, len(m.points)),
                       lazy_patches=True)
    with pytest.raises(ValueError, match="rational"):
        StreamedSurface(rational)


def test_jobs_on_threads_come_in_order_and_errors_reach_the_caller():
    from c1surf.evaluation.stream.welded import in_order_on_threads

    assert list(in_order_on_threads(range(100), lambda j: j * j, per_task=3)) == [j * j for j in range(100)]

    def fails(j):
        if j == 57:
            raise ValueError("job 57")
        return j

    seen = []
    with pytest.raises(ValueError, match="job 57"):
        for value in in_order_on_threads(range(100), fails, per_task=4):
            seen.append(value)
    assert seen == list(range(len(seen))) and len(seen) <= 57
