"""Surface.patch_blocks / patch_source: the patch coefficients by blocks, bit for bit the in-memory arrays."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from c1surf.construction.stencils import layout
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.io.meshes.read import read_mesh

ROOT = Path(__file__).resolve().parents[2]
MESHES = ["cube", "dodecahedron", "twisted", "high_valence", "hexagon_all_six_valent"]


def _small_blocks(monkeypatch, tiny: bool) -> None:
    """With ``tiny``, product blocks of a few points (every block boundary is exercised)."""
    if tiny:
        monkeypatch.setattr(layout, "_BLOCK_POINTS", 40)
        monkeypatch.setattr(layout, "_THREAD_POINTS", 200)


def _surfaces(name: str, **kwargs):
    m = read_mesh(ROOT / "sample_meshes" / f"{name}.obj")
    eager = Surface(m.face_sizes, m.face_vertices, m.points, **kwargs)
    lazy = Surface(m.face_sizes, m.face_vertices, m.points, lazy_patches=True, **kwargs)
    return eager, lazy


@pytest.mark.parametrize("tiny", [False, True], ids=["default blocks", "tiny blocks"])
@pytest.mark.parametrize("name", MESHES)
def test_any_patches_in_any_order_equal_the_arrays(monkeypatch, name, tiny):
    _small_blocks(monkeypatch, tiny)
    eager, lazy = _surfaces(name)
    source = lazy.patch_source(cache_bytes=1 << 12 if tiny else None)
    for kind, whole in enumerate((eager.biquadratic, eager.bicubic)):
        order = np.random.default_rng(kind).permutation(len(whole))
        order = np.concatenate([order, order[: len(order) // 3]])  # repeats, after the cache let them go
        coefficients, weights = source.coefficients(kind, order)
        assert weights is None and coefficients.dtype == np.float64
        assert np.array_equal(coefficients, whole[order])


@pytest.mark.parametrize("name", MESHES)
def test_blocks_cover_every_patch_once_in_order(name):
    eager, lazy = _surfaces(name)
    blocks = list(lazy.patch_blocks(size=7))
    ids = np.concatenate([b.ids for b in blocks])
    assert np.array_equal(ids, np.arange(eager.n_patches))
    for kind, whole in enumerate((eager.biquadratic, eager.bicubic)):
        mine = [b.coefficients for b in blocks if b.kind == kind]
        assert np.array_equal(np.concatenate(mine) if mine else whole[:0], whole)
    assert lazy._patches is None  # the blocks made no whole array
    assert np.array_equal(lazy.biquadratic, eager.biquadratic) and np.array_equal(lazy.bicubic, eager.bicubic)
    assert np.array_equal(lazy.refined_points, eager.refined_points)


@pytest.fixture(scope="module")
def open_mesh_surfaces():
    """(eager, lazy) Surfaces of an open mesh, whose bicubic patches are kept at real corners only."""
    path = ROOT.parent / "shared" / "meshes" / "pmp-library" / "hole_capsule.obj"
    if not path.exists():
        pytest.skip(f"{path} is not here")
    m = read_mesh(path)
    return (Surface(m.face_sizes, m.face_vertices, m.points),
            Surface(m.face_sizes, m.face_vertices, m.points, lazy_patches=True))


def test_open_mesh_blocks_keep_only_the_kept_patches(open_mesh_surfaces):
    """An open mesh keeps only the bicubic patches at real corners (PatchLayout.keep)."""
    eager, lazy = open_mesh_surfaces
    assert lazy.stages[-1].parts[1].keep is not None
    source = lazy.patch_source(cache_bytes=1)
    assert source.counts == (len(eager.biquadratic), len(eager.bicubic))
    order = np.random.default_rng(0).permutation(len(eager.bicubic))
    assert np.array_equal(source.coefficients(1, order)[0], eager.bicubic[order])


def test_rational_blocks_give_points_and_weights():
    m = read_mesh(ROOT / "sample_meshes" / "twisted.obj")
    weights = 1.0 + 0.5 * np.sin(np.arange(len(m.points)))
    eager = Surface(m.face_sizes, m.face_vertices, m.points, weights=weights)
    lazy = Surface(m.face_sizes, m.face_vertices, m.points, weights=weights, lazy_patches=True)
    for block in lazy.patch_blocks(size=50):
        whole = (eager.biquadratic, eager.bicubic)[block.kind]
        whole_weights = (eager.biquadratic_weights, eager.bicubic_weights)[block.kind]
        local = block.ids - (0 if block.kind == 0 else len(eager.biquadratic))
        assert np.array_equal(block.coefficients, whole[local]) and np.array_equal(block.weights, whole_weights[local])


def test_update_points_follows_in_blocks_and_lazy_arrays():
    eager, lazy = _surfaces("twisted", options=SurfaceOptions(blend=0.3))
    moved = eager.points + 0.01 * np.cos(np.arange(eager.points.size)).reshape(eager.points.shape)
    eager.update_points(moved)
    lazy.update_points(moved)
    assert lazy._patches is None
    source = lazy.patch_source()
    assert np.array_equal(source.coefficients(0, np.arange(len(eager.biquadratic)))[0], eager.biquadratic)
    assert np.array_equal(lazy.bicubic, eager.bicubic)
    assert "apply patches" in lazy.timings


@pytest.mark.parametrize("name", MESHES)
def test_whole_arrays_from_the_source_are_the_surfaces(name):
    eager, lazy = _surfaces(name)
    biquadratic, bicubic = lazy.patch_source().arrays()
    assert lazy._patches is None
    assert np.array_equal(biquadratic, eager.biquadratic) and np.array_equal(bicubic, eager.bicubic)
    assert biquadratic.shape == eager.biquadratic.shape and bicubic.shape == eager.bicubic.shape


def test_whole_arrays_of_an_open_mesh_keep_only_the_kept_patches(open_mesh_surfaces):
    eager, lazy = open_mesh_surfaces
    biquadratic, bicubic = lazy.patch_source().arrays()
    assert np.array_equal(biquadratic, eager.biquadratic) and np.array_equal(bicubic, eager.bicubic)


def _span_rows_equal_the_arrays(source, wholes) -> None:
    """Every product span's patches, and any of their coefficient rows (``span_rows``), equal the arrays."""
    for kind, whole in enumerate(wholes):
        spans, rng = source.product_spans(kind), np.random.default_rng(kind)
        assert [p0 for _, _, p0, _ in spans[1:]] == [p1 for _, _, _, p1 in spans[:-1]]  # in order, no gap
        assert (spans[0][2], spans[-1][3]) == (0, len(whole)) if spans else len(whole) == 0
        flat = whole.reshape(len(whole), -1, whole.shape[-1])
        for g, b, p0, p1 in spans:
            rows = rng.integers(0, (p1 - p0) * flat.shape[1], (3, 17))
            patch, coefficient = np.divmod(rows, flat.shape[1])
            assert np.array_equal(source.span_rows(kind, g, b, rows), flat[p0 + patch, coefficient])


@pytest.mark.parametrize("tiny", [False, True], ids=["default blocks", "tiny blocks"])
@pytest.mark.parametrize("name", MESHES)
def test_span_rows_equal_the_arrays(monkeypatch, name, tiny):
    _small_blocks(monkeypatch, tiny)
    eager, lazy = _surfaces(name)
    _span_rows_equal_the_arrays(lazy.patch_source(), (eager.biquadratic, eager.bicubic))


def test_span_rows_of_an_open_mesh_keep_only_the_kept_patches(open_mesh_surfaces):
    eager, lazy = open_mesh_surfaces
    assert lazy.patch_source().layouts[1].keep is not None  # the case: bicubic patches kept at real corners only
    _span_rows_equal_the_arrays(lazy.patch_source(), (eager.biquadratic, eager.bicubic))


def test_threads_asking_for_the_same_blocks_get_the_arrays(monkeypatch):
    """A streamed tessellation asks for coefficients from several threads: each block is made by one of them
    (the others wait for it), the cache stays within its bytes, and every answer is the in-memory array's."""
    from concurrent.futures import ThreadPoolExecutor

    _small_blocks(monkeypatch, True)
    eager, lazy = _surfaces("high_valence")
    source = lazy.patch_source(cache_bytes=1 << 13)
    made = []
    original = source._made_block
    monkeypatch.setattr(source, "_made_block", lambda *key: made.append(key) or original(*key))
    whole = [eager.biquadratic, eager.bicubic]

    def ask(seed):
        rng = np.random.default_rng(seed)
        kind = seed % 2
        order = rng.integers(0, len(whole[kind]), 200)
        return kind, order, source.coefficients(kind, order)[0]

    with ThreadPoolExecutor(4) as pool:
        answers = list(pool.map(ask, range(40)))
    for kind, order, coefficients in answers:
        assert np.array_equal(coefficients, whole[kind][order])
    assert source._cached <= max(1 << 13, max(rows.nbytes for rows in source._cache.values()))
    assert not source._making and len(made) >= len(source._cache)
