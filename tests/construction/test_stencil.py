"""Surface.stencil(): the whole construction as one sparse matrix, for every option; and each stage's matrix is its map."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import issparse

from c1surf.construction.stages import Stage
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.io.meshes.obj import read_obj

from conftest import CLOSED_SAMPLES, SAMPLES, fan, grid, open_cylinder, polygon_mesh, single_polygon, slab_with_polygons
from test_extensions import regular_torus, split_cube

TOLERANCE = 1e-13  # relative to the bounding-box diagonal of the input points


def rows_of(surface: Surface) -> np.ndarray:
    """The coefficient rows the stencil must reproduce: biquadratic, then bicubic."""
    d = surface.biquadratic.shape[-1]
    return np.concatenate([surface.biquadratic.reshape(-1, d), surface.bicubic.reshape(-1, d)])


def assert_reproduces(surface: Surface, points: np.ndarray, flat: bool = False):
    scale = np.linalg.norm(np.ptp(points[:, :3], axis=0))
    S = surface.stencil(flat=flat)
    assert issparse(S)
    got = (S @ points.ravel()).reshape(-1, points.shape[1]) if flat else S @ points
    assert got.shape == rows_of(surface).shape
    assert np.abs(got - rows_of(surface)).max() < TOLERANCE * scale


def moebius_strip(n=12, width=0.3):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    rings = [np.c_[(1 + w * np.cos(t / 2)) * np.cos(t), (1 + w * np.cos(t / 2)) * np.sin(t), w * np.sin(t / 2)] for w in (-width, width)]
    faces = [[i, i + 1, n + i + 1, n + i] for i in range(n - 1)] + [[n - 1, n, 0, 2 * n - 1]]
    return polygon_mesh(faces, np.concatenate(rings))


def vertex_normals(sizes, vertices, points, seed=1):
    """Area-weighted vertex normals, turned at random (NaN where a vertex has none)."""
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    normals = np.zeros_like(points)
    for f in range(len(sizes)):
        corners = vertices[offsets[f] : offsets[f + 1]]
        p = points[corners] - points[corners].mean(axis=0)
        normals[corners] += np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)
    normals += 0.2 * np.random.default_rng(seed).normal(size=normals.shape) * np.linalg.norm(normals, axis=1, keepdims=True)
    return normals / np.linalg.norm(normals, axis=1, keepdims=True)


def sample(name):
    mesh = read_obj(SAMPLES / name)
    return mesh.face_sizes, mesh.face_vertices, mesh.points


@pytest.mark.parametrize("name", CLOSED_SAMPLES)
def test_stencil_reproduces_every_sample_mesh(name):
    sizes, vertices, points = sample(name)
    surface = Surface(sizes, vertices, points)
    assert_reproduces(surface, points)
    assert surface.stencil().shape == (9 * len(surface.biquadratic) + 16 * len(surface.bicubic), len(points))


MESHES = {
    "twisted": lambda: sample("twisted.obj"),
    "high_valence": lambda: sample("high_valence.obj"),
    "hexagon_six_valent": lambda: sample("hexagon_six_valent.obj"),  # even holes sharing B points: perturbation
    "tetrahedron": lambda: sample("tetrahedron.obj"),  # triangles everywhere
    "grid": lambda: grid(5, lambda x, y: 0.2 * np.sin(x) * np.cos(y)),  # open: ghost layer
    "fan": lambda: fan(7),
    "cylinder": lambda: open_cylinder(),
    "hexagon": lambda: single_polygon(6),
    "moebius": moebius_strip,  # non-orientable: double cover
    "slab": slab_with_polygons,
}
OPTIONS = {
    "shape": dict(blend=0.2, alpha=0.6, beta=0.3),
    "corners": dict(tangent_rule="corners", blend=0.8),
    "parametric": dict(triangles="parametric"),
    "interpolate": dict(interpolate_vertices=True),
    "interpolate corners parametric": dict(interpolate_vertices=True, tangent_rule="corners", triangles="parametric"),
}


@pytest.mark.parametrize("option", OPTIONS)
@pytest.mark.parametrize("mesh", MESHES)
def test_stencil_for_every_option(mesh, option):
    sizes, vertices, points = MESHES[mesh]()
    surface = Surface(sizes, vertices, points, SurfaceOptions(**OPTIONS[option]))
    assert_reproduces(surface, points)
    assert_reproduces(surface, points, flat=True)


@pytest.mark.parametrize("mesh", ["twisted", "grid", "moebius", "tetrahedron"])
def test_stencil_with_blend_ratios_per_face_and_vertex(mesh):
    sizes, vertices, points = MESHES[mesh]()
    rng = np.random.default_rng(len(points))
    face_blend, vertex_blend = rng.uniform(0, 1, len(sizes)), rng.uniform(0, 1, len(points))
    face_blend[::3], vertex_blend[::2] = np.nan, -1  # unset
    surface = Surface(sizes, vertices, points, face_blend=face_blend, vertex_blend=vertex_blend)
    assert_reproduces(surface, points)


@pytest.mark.parametrize("levels, mesh", [(0, regular_torus), (1, regular_torus), (1, split_cube), ("auto", split_cube),
                                          ("auto", lambda: sample("high_valence.obj")), (2, split_cube)])
def test_stencil_for_every_refinement_count(levels, mesh):
    sizes, vertices, points = mesh()
    surface = Surface(sizes, vertices, points, SurfaceOptions(refinements=levels))
    assert_reproduces(surface, points)


@pytest.mark.parametrize("mesh", ["twisted", "grid", "moebius", "tetrahedron"])
def test_rational_stencil_gives_the_euclidean_coefficients_for_fixed_weights(mesh):
    sizes, vertices, points = MESHES[mesh]()
    weights = np.random.default_rng(4).uniform(0.5, 2.0, len(points))
    surface = Surface(sizes, vertices, points, weights=weights)
    assert_reproduces(surface, points)
    assert_reproduces(surface, points, flat=True)
    # it is (S_h (w x)) / (S_h w) with S_h the polynomial surface's stencil
    S_h = Surface(sizes, vertices, points).stencil()
    expected = (S_h @ (points * weights[:, None])) / (S_h @ weights)[:, None]
    np.testing.assert_allclose(surface.stencil() @ points, expected, rtol=0, atol=TOLERANCE * np.abs(points).max())
    # new points, same weights: the same stencil
    moved = points + np.random.default_rng(5).normal(scale=0.01, size=points.shape)
    stencil = surface.stencil()
    surface.update_points(moved)
    assert surface.stencil() is stencil
    assert_reproduces(surface, moved)
    surface.update_points(moved, weights=weights[::-1].copy())  # new weights: a new stencil
    assert surface.stencil() is not stencil
    assert_reproduces(surface, moved)


@pytest.mark.parametrize("mesh", ["twisted", "grid", "tetrahedron"])
@pytest.mark.parametrize("option", ["interpolate", "interpolate corners parametric"])
@pytest.mark.parametrize("rational", [False, True])
def test_vertex_normals_need_the_flat_stencil(mesh, option, rational):
    sizes, vertices, points = MESHES[mesh]()
    normals = vertex_normals(sizes, vertices, points)
    weights = np.random.default_rng(6).uniform(0.5, 2.0, len(points)) if rational else None
    surface = Surface(sizes, vertices, points, SurfaceOptions(alpha=0.8, **OPTIONS[option]), vertex_normals=normals,
                      weights=weights)
    assert any(stage.mixes_coordinates for stage in surface.stages)
    with pytest.raises(ValueError, match=r"mixes the coordinates.*stencil\(flat=True\)"):
        surface.stencil()
    assert_reproduces(surface, points, flat=True)
    assert surface.stencil(flat=True).shape == (rows_of(surface).size, points.size)


def test_stencil_carries_extra_columns_like_positions():
    sizes, vertices, points = sample("twisted.obj")
    extra = np.c_[points, np.random.default_rng(7).normal(size=(len(points), 2))]
    surface = Surface(sizes, vertices, extra)
    assert surface.stencil().shape[1] == len(points)
    assert_reproduces(surface, extra)
    assert_reproduces(surface, extra, flat=True)


@pytest.mark.parametrize("mesh", ["twisted", "grid", "hexagon_six_valent"])
def test_stencil_drives_new_points(mesh):
    """Animation: the stencil of one surface maps any new points of the same connectivity."""
    sizes, vertices, points = MESHES[mesh]()
    surface = Surface(sizes, vertices, points)
    S = surface.stencil()
    moved = points * (1 + 0.01 * np.random.default_rng(8).normal(size=(len(points), 1)))
    np.testing.assert_allclose(S @ moved, rows_of(Surface(sizes, vertices, moved)), rtol=0,
                               atol=TOLERANCE * np.linalg.norm(np.ptp(points, axis=0)))


@pytest.mark.parametrize("mesh, options, kwargs", [
    ("hexagon_six_valent", {}, {}),
    ("grid", {"interpolate_vertices": True}, {}),
    ("twisted", {"interpolate_vertices": True, "alpha": 0.8}, {"normals": True}),
    ("moebius", {}, {"weights": True}),
])
def test_every_stage_is_its_matrix(mesh, options, kwargs):
    """apply and matrix() of each stage are one map (flattened for a stage that mixes coordinates)."""
    sizes, vertices, points = MESHES[mesh]()
    if kwargs.get("normals"):
        kwargs = {"vertex_normals": vertex_normals(sizes, vertices, points)}
    elif kwargs.get("weights"):
        kwargs = {"weights": np.random.default_rng(9).uniform(0.5, 2, len(points))}
    surface = Surface(sizes, vertices, points, SurfaceOptions(**options), **kwargs)
    x = points if surface.weights is None else np.c_[points * surface.weights[:, None], surface.weights]
    names = []
    for stage in surface.stages:
        assert isinstance(stage, Stage)
        names.append(stage.name)
        y = stage.apply(x)
        assert y.shape == (stage.shape[0], x.shape[1]) and stage.shape[1] == x.shape[0]
        if stage.mixes_coordinates:
            matrix = stage.matrix(x.shape[1], x[:, -1] if surface.weights is not None else None)
            np.testing.assert_allclose((matrix @ x.ravel()).reshape(y.shape), y, rtol=0, atol=1e-13 * np.abs(x).max())
        else:
            np.testing.assert_allclose(stage.matrix() @ x, y, rtol=0, atol=1e-13 * np.abs(x).max())
        x = y
    assert names[0] == "place" and names[-1] == "patches"
    assert surface.stage("patches") is surface.stages[-1]
    with pytest.raises(KeyError):
        surface.stage("no such stage")


@pytest.mark.parametrize("name", ["twisted", "high_valence", "hexagon_six_valent", "triangular_prism"])
def test_first_stages_without_their_matrices_give_the_matrices_bits(name):
    """The placement (a closed mesh's) and the plain first Doo-Sabin step are applied without scipy.sparse;
    they give the bits of their matrices' products, -0.0 turned into 0.0 as those products turn it."""
    mesh = read_obj(SAMPLES / f"{name}.obj")
    points = np.array(mesh.points)
    points[::3, 0] = -0.0
    surface = Surface(mesh.face_sizes, mesh.face_vertices, points, SurfaceOptions(blend=0.3))
    x = points
    for stage in surface.stages[:2]:
        assert stage.name in ("place", "doo_sabin_1") and stage._matrix is None
        y = stage.apply(x)
        assert y.tobytes() == (stage.matrix() @ x).tobytes()
        x = y
