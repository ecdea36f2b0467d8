"""Checks of the project's sample meshes (sample_meshes/*.obj).

The OBJ files are parsed with a tiny local reader (polygons kept as polygons);
c1surf's own reader is deliberately not used, so these tests check the data
independently of the code under test.
"""

from __future__ import annotations

import filecmp
import subprocess
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = ROOT / "sample_meshes"
GENERATOR = SAMPLES / "generate.py"

# name -> intended genus
EXPECTED_GENUS = {
    "cube": 0,
    "tetrahedron": 0,
    "octahedron": 0,
    "icosahedron": 0,
    "dodecahedron": 0,
    "triangular_prism": 0,
    "hexagonal_prism": 0,
    "twisted": 0,
    "torus": 1,
    "double_torus": 2,
    "high_valence": 0,
    "hexagon_six_valent": 0,
    "hexagon_all_six_valent": 0,
}
NAMES = sorted(EXPECTED_GENUS)


# ---------------------------------------------------------------------------
# tiny OBJ reader and mesh helpers
# ---------------------------------------------------------------------------


def read_obj(path):
    """Return (V x 3 float array, list of faces as lists of 0-based indices)."""
    verts, faces = [], []
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        parts = line.split()
        if not parts or parts[0].startswith("#"):
            continue
        if parts[0] == "v":
            assert len(parts) == 4, line
            verts.append([float(x) for x in parts[1:]])
        elif parts[0] == "f":
            face = []
            for tok in parts[1:]:
                i = int(tok.split("/")[0])
                face.append(i - 1 if i > 0 else len(verts) + i)
            faces.append(face)
        else:
            raise AssertionError(f"unexpected OBJ line in {path}: {line!r}")
    return np.asarray(verts, dtype=float), faces


def half_edges(faces):
    return Counter((a, b) for f in faces for a, b in zip(f, f[1:] + f[:1]))


def valences(faces, nverts):
    val = [0] * nverts
    for (a, _b) in half_edges(faces):
        val[a] += 1
    return val


def newell_normal(P, f):
    Q = P[f]
    return np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0) / 2.0


def signed_volume(P, faces):
    vol = 0.0
    for f in faces:
        for i in range(1, len(f) - 1):
            vol += np.dot(P[f[0]], np.cross(P[f[i]], P[f[i + 1]])) / 6.0
    return vol


@pytest.fixture(scope="module", params=NAMES)
def mesh(request):
    name = request.param
    P, F = read_obj(SAMPLES / f"{name}.obj")
    return name, P, F


def load(name):
    return read_obj(SAMPLES / f"{name}.obj")


# ---------------------------------------------------------------------------
# generic properties, every sample mesh
# ---------------------------------------------------------------------------


def test_sample_set_is_complete():
    on_disk = {p.stem for p in SAMPLES.glob("*.obj")}
    assert on_disk == set(EXPECTED_GENUS)


def test_header_comment(mesh):
    name, _P, _F = mesh
    head = (SAMPLES / f"{name}.obj").read_text(encoding="utf-8").splitlines()[:3]
    assert head[0].startswith("#") and name in head[0]
    assert any("generate.py" in line for line in head)


def test_faces_well_formed(mesh):
    name, P, F = mesh
    assert len(P) > 0 and len(F) > 0
    for f in F:
        assert len(f) >= 3, (name, f)
        assert len(set(f)) == len(f), f"{name}: repeated vertex in face {f}"
        assert all(0 <= i < len(P) for i in f), (name, f)


def test_every_vertex_used(mesh):
    name, P, F = mesh
    assert {i for f in F for i in f} == set(range(len(P))), name


def test_closed_manifold_consistently_oriented(mesh):
    """Every undirected edge lies in exactly two faces, once in each direction."""
    name, _P, F = mesh
    he = half_edges(F)
    for (a, b), count in he.items():
        assert count == 1, f"{name}: half-edge {(a, b)} used {count} times"
        assert he.get((b, a), 0) == 1, f"{name}: edge {(a, b)} is a boundary or misoriented"


def test_manifold_vertices(mesh):
    """The faces around each vertex form a single cycle (no pinched vertices)."""
    name, P, F = mesh
    turn = {}  # (v, w) -> next neighbour of v, rotating around v through one face
    for f in F:
        k = len(f)
        for i in range(k):
            turn[(f[i], f[(i + 1) % k])] = f[(i - 1) % k]
    val = valences(F, len(P))
    out = {}
    for (a, b) in turn:
        out.setdefault(a, b)
    for v in range(len(P)):
        start = w = out[v]
        steps = 0
        while True:
            w = turn[(v, w)]
            steps += 1
            if w == start or steps > val[v]:
                break
        assert steps == val[v], f"{name}: vertex {v} is not a manifold vertex"


def test_no_low_valence(mesh):
    name, P, F = mesh
    val = valences(F, len(P))
    assert min(val) >= 3, f"{name}: vertex of valence {min(val)}"


def test_no_two_faces_share_two_edges(mesh):
    name, _P, F = mesh
    owner = {}
    for fi, f in enumerate(F):
        for a, b in zip(f, f[1:] + f[:1]):
            owner[(a, b)] = fi
    pairs = Counter()
    for (a, b), fi in owner.items():
        if a < b:
            pairs[frozenset((fi, owner[(b, a)]))] += 1
    assert max(pairs.values()) == 1, name


def test_euler_characteristic_matches_genus(mesh):
    name, P, F = mesh
    E = len(half_edges(F)) // 2
    chi = len(P) - E + len(F)
    assert chi == 2 - 2 * EXPECTED_GENUS[name], f"{name}: V - E + F = {chi}"


def test_non_degenerate_faces(mesh):
    name, P, F = mesh
    scale = np.ptp(P, axis=0).max()
    for f in F:
        assert np.linalg.norm(newell_normal(P, f)) > 1e-4 * scale**2, f"{name}: degenerate face {f}"
        Q = P[f]
        edge_len = np.linalg.norm(Q - np.roll(Q, -1, axis=0), axis=1)
        assert edge_len.min() > 1e-4 * scale, f"{name}: zero-length edge in {f}"


def test_outward_orientation(mesh):
    name, P, F = mesh
    vol = signed_volume(P, F)
    assert vol > 0, f"{name}: signed volume {vol} (faces oriented inward)"
    # the volume is translation invariant for a closed mesh
    assert np.isclose(signed_volume(P + np.array([3.0, -2.0, 5.0]), F), vol)


def test_faces_locally_convex(mesh):
    """Each corner turns left about the face's Newell normal (no reflex or
    straight corners), so the sample cells are reasonable input."""
    name, P, F = mesh
    for f in F:
        n = newell_normal(P, f)
        n /= np.linalg.norm(n)
        Q = P[f]
        for i in range(len(f)):
            d1 = Q[i] - Q[i - 1]
            d2 = Q[(i + 1) % len(f)] - Q[i]
            s = np.dot(np.cross(d1, d2), n) / (np.linalg.norm(d1) * np.linalg.norm(d2))
            assert s > 0.05, f"{name}: corner {f[i]} of face {f} is (nearly) reflex"


# ---------------------------------------------------------------------------
# per-file properties
# ---------------------------------------------------------------------------


def face_sizes(F):
    return Counter(len(f) for f in F)


@pytest.mark.parametrize(
    "name, sizes",
    [
        ("cube", {4: 6}),
        ("tetrahedron", {3: 4}),
        ("octahedron", {3: 8}),
        ("icosahedron", {3: 20}),
        ("dodecahedron", {5: 12}),
        ("triangular_prism", {3: 2, 4: 3}),
        ("hexagonal_prism", {4: 6, 6: 2}),
    ],
)
def test_simple_solids_face_sizes(name, sizes):
    _P, F = load(name)
    assert dict(face_sizes(F)) == sizes


@pytest.mark.parametrize(
    "name, val",
    [("cube", 3), ("tetrahedron", 3), ("octahedron", 4), ("icosahedron", 5),
     ("dodecahedron", 3), ("triangular_prism", 3), ("hexagonal_prism", 3)],
)
def test_simple_solids_valence(name, val):
    P, F = load(name)
    assert set(valences(F, len(P))) == {val}


def test_twisted():
    P, F = load("twisted")
    sizes = face_sizes(F)
    for k in (3, 4, 5, 6):
        assert sizes[k] >= 1, f"twisted has no {k}-gon"
    val = set(valences(F, len(P)))
    assert {3, 4, 5} <= val
    # not mirror- or rotation-symmetric about the vertical axis through the centroid
    c = P.mean(axis=0)
    Q = P - c
    for R in (np.diag([-1.0, 1.0, 1.0]), np.diag([1.0, -1.0, 1.0]), np.diag([-1.0, -1.0, 1.0])):
        img = Q @ R.T
        d = np.min(np.linalg.norm(img[:, None, :] - Q[None, :, :], axis=2), axis=1)
        assert d.max() > 1e-3
    # some hexagon is not centrally symmetric (opposite corners' midpoints differ)
    hexes = [P[f] for f in F if len(f) == 6]
    assert any(np.linalg.norm((H[:3] + H[3:]) / 2 - H.mean(axis=0), axis=1).max() > 1e-3 for H in hexes)


def test_torus():
    P, F = load("torus")
    assert dict(face_sizes(F)) == {4: 96}
    assert set(valences(F, len(P))) == {4}


def test_double_torus():
    P, F = load("double_torus")
    E = len(half_edges(F)) // 2
    assert len(P) - E + len(F) == -2
    assert set(face_sizes(F)) == {4}


def test_high_valence():
    P, F = load("high_valence")
    assert max(valences(F, len(P))) >= 10
    assert max(len(f) for f in F) >= 10


def _hexagon_corner_valences(name):
    P, F = load(name)
    val = valences(F, len(P))
    return [[val[v] for v in f] for f in F if len(f) == 6], P, F


def test_hexagon_six_valent():
    hexes, P, F = _hexagon_corner_valences("hexagon_six_valent")
    assert any(6 in h for h in hexes), "no hexagon with a 6-valent corner"


def test_hexagon_all_six_valent():
    hexes, P, F = _hexagon_corner_valences("hexagon_all_six_valent")
    assert any(all(v == 6 for v in h) for h in hexes), "no hexagon with all corners 6-valent"


@pytest.mark.parametrize("name", ["hexagon_six_valent", "hexagon_all_six_valent"])
def test_jittered_meshes_not_symmetric(name):
    """The jitter must break symmetry: no coordinate value repeats exactly."""
    P, _F = load(name)
    for k in range(3):
        assert len(np.unique(P[:, k])) == len(P), f"{name}: repeated coordinate on axis {k}"


# ---------------------------------------------------------------------------
# the generator
# ---------------------------------------------------------------------------


def test_generator_is_deterministic(tmp_path):
    """Regenerating into a fresh directory gives byte-identical files."""
    subprocess.run([sys.executable, str(GENERATOR), "--out", str(tmp_path)], check=True)
    generated = sorted(p.name for p in tmp_path.iterdir())
    committed = sorted(p.name for p in SAMPLES.iterdir() if p.suffix == ".obj" or p.name == "README.md")
    assert generated == committed
    for fname in generated:
        assert filecmp.cmp(tmp_path / fname, SAMPLES / fname, shallow=False), (
            f"{fname} differs from the generator output; rerun sample_meshes/generate.py"
        )
