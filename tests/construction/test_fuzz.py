"""Property-based: any mesh or file ends in a G1 surface or a clean one-line error."""
from __future__ import annotations

import numpy as np
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from c1surf.cli.main import main
from c1surf.mesh.errors import TopologyError
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.construction.surface import Surface
from c1surf.evaluation.tessellate import tessellate

FUZZ = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


@st.composite
def polygon_meshes(draw):
    """A wavy quad grid, then random merges (n-gons, odd valences), deletions (boundaries, pinches) and flips."""
    nx, ny = draw(st.integers(2, 6)), draw(st.integers(2, 6))
    seed = draw(st.integers(0, 2**31))
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0), indexing="ij")
    points = np.c_[x.ravel(), y.ravel(), 0.3 * rng.normal(size=x.size)]
    k = lambda i, j: i * (ny + 1) + j  # noqa: E731
    faces = [[k(i, j), k(i + 1, j), k(i + 1, j + 1), k(i, j + 1)] for i in range(nx) for j in range(ny)]
    if draw(st.booleans()):  # split some quads into triangles
        for f in rng.choice(len(faces), size=len(faces) // 3, replace=False):
            a, b, c, d = faces[f]
            faces[f] = [a, b, c]
            faces.append([a, c, d])
    for _ in range(draw(st.integers(0, 6))):  # merge two faces that share exactly one edge
        f = int(rng.integers(len(faces)))
        g = int(rng.integers(len(faces)))
        if f == g:
            continue
        shared = set(faces[f]) & set(faces[g])
        if len(shared) != 2:
            continue
        a = faces[f]
        n = len(a)
        i = next((i for i in range(n) if a[i] in shared and a[(i + 1) % n] in shared), None)
        if i is None:  # the two shared vertices are not an edge of f
            continue
        u, v = a[i], a[(i + 1) % n]
        b = faces[g]
        j = b.index(v)
        if b[(j + 1) % len(b)] != u:
            continue
        merged = a[: i + 1] + [b[(j + 1 + t) % len(b)] for t in range(1, len(b) - 1)] + a[i + 1 :]
        if len(set(merged)) != len(merged):
            continue
        faces[f] = merged
        del faces[g]
    for _ in range(draw(st.integers(0, 3))):  # delete faces: boundaries, holes, maybe pinches
        if len(faces) > 1:
            del faces[int(rng.integers(len(faces)))]
    flips = draw(st.integers(0, 3))
    for f in rng.choice(len(faces), size=min(flips, len(faces)), replace=False):
        faces[f] = faces[f][::-1]
    return points, faces


@FUZZ
@given(polygon_meshes())
def test_random_meshes_give_g1_or_a_clean_error(mesh):
    points, faces = mesh
    sizes = np.array([len(f) for f in faces])
    vertices = np.concatenate([np.asarray(f) for f in faces])
    try:
        surface = Surface(sizes, vertices, points)
    except TopologyError as e:
        assert str(e) and "\n" not in str(e)
        return
    report = measure_smoothness([surface.biquadratic, surface.bicubic])
    assert report.overshared_edges == 0
    assert report.max_normal_jump < 1e-9, report
    tess = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, 3)
    assert np.isfinite(tess.points).all() and np.isfinite(tess.normals).all()


OBJ_LINES = st.one_of(
    st.builds(lambda *c: "v " + " ".join(c), *[st.sampled_from(["0", "1", "-2.5", "1e3", "nan", "inf", "x", ""])] * 3),
    st.builds(lambda *i: "f " + " ".join(i), *[st.sampled_from(["1", "2", "3", "4", "-1", "0", "9", "1/1", "2//3", "a", ""])] * 4),
    st.sampled_from(["", "# comment", "vt 0 1", "vn 0 0 1", "g part", "s off", "usemtl m", "l 1 2", "\\", "f", "v"]),
    st.text(max_size=12),
)


def run_cli(tmp_path, data: bytes, suffix: str):
    path = tmp_path / f"in{suffix}"
    path.write_bytes(data)
    out = tmp_path / "out.ply"
    if out.exists():
        out.unlink()
    result = CliRunner().invoke(main, ["convert", str(path), "-o", str(out), "-r", "2", "-q"])
    assert result.exit_code in (0, 1), result.output
    if result.exit_code == 1:
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("c1surf: error: ")
        assert not out.exists()
    else:
        assert out.exists()


@FUZZ
@given(st.lists(OBJ_LINES, max_size=30))
def test_random_obj_text_never_crashes(tmp_path, lines):
    run_cli(tmp_path, "\n".join(lines).encode("utf-8", "surrogatepass"), ".obj")


@FUZZ
@given(st.binary(max_size=400), st.sampled_from(["ascii", "binary_little_endian", "binary_big_endian"]), st.integers(0, 5))
def test_random_ply_bytes_never_crash(tmp_path, body, encoding, n_faces):
    header = (
        f"ply\nformat {encoding} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {n_faces}\nproperty list uchar int vertex_indices\nend_header\n"
    ).encode()
    run_cli(tmp_path, header + body, ".ply")


@FUZZ
@given(st.binary(max_size=300), st.sampled_from([".obj", ".ply"]))
def test_arbitrary_bytes_never_crash(tmp_path, data, suffix):
    run_cli(tmp_path, data, suffix)
