"""Interior valence-2 vertices are dissolved into the edge they split (mesh.valence_two): G1, and what moves."""
from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from c1surf.api import check_surface, surface_from_file, tessellate_surface
from c1surf.cli.main import main
from c1surf.mesh.valence_two import dissolve_valence_two, valence_two_vertices


def obj(path, points, faces, tags=""):
    path.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in points)
                    + "".join("f " + " ".join(str(v + 1) for v in f) + "\n" for f in faces) + tags)
    return path


CUBE = [(0, 0, 0), (2, 0, 0), (2, 2, 0), (0, 2, 0), (0, 0, 2), (2, 0, 2), (2, 2, 2), (0, 2, 2)]
CUBE_FACES = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
BOTTOM, FRONT = 0, 2  # the two faces at the cube edge 0-1


def split_cube(kind):
    """(points, faces, valence-2 vertices): the cube with vertices of valence 2 at its edge 0 - 1.

    - "quads": vertex 8 on the edge, in the bottom face and the front face (both become 5-gons);
    - "row": vertices 8 and 9 on the edge, one after the other (two 6-gons);
    - "quad-triangle": vertex 8 below the edge, in the bottom face and a triangle (8, 1, 0) that now
      borders the front face along 0 - 1;
    - "triangles": vertex 8 off the edge, in two triangles (0, 1, 8) and (1, 0, 8) between the
      bottom and the front face (a thin tent along the edge).
    """
    faces = [list(f) for f in CUBE_FACES]
    if kind == "quads":
        faces[BOTTOM], faces[FRONT] = [0, 3, 2, 1, 8], [0, 8, 1, 5, 4]
        return list(CUBE) + [(1, 0, 0)], faces, [8]
    if kind == "row":
        faces[BOTTOM], faces[FRONT] = [0, 3, 2, 1, 9, 8], [0, 8, 9, 1, 5, 4]
        return list(CUBE) + [(2 / 3, 0, 0), (4 / 3, 0, 0)], faces, [8, 9]
    if kind == "quad-triangle":
        faces[BOTTOM] = [0, 3, 2, 1, 8]
        return list(CUBE) + [(1, 0.3, -0.4)], faces + [[8, 1, 0]], [8]
    assert kind == "triangles"
    return list(CUBE) + [(1, -0.3, -0.3)], faces + [[0, 1, 8], [1, 0, 8]], [8]


def sorted_coefficients(surface):
    return np.sort(np.concatenate([surface.biquadratic.reshape(-1, 3), surface.bicubic.reshape(-1, 3)]), axis=0)


@pytest.mark.parametrize("kind", ["quads", "row", "quad-triangle", "triangles"])
def test_valence_two_vertices_are_dissolved_and_the_surface_is_g1(tmp_path, kind):
    points, faces, extra = split_cube(kind)
    sizes, flat = np.array([len(f) for f in faces]), np.concatenate(faces)
    assert valence_two_vertices(sizes, flat, len(points)).tolist() == extra
    new_sizes, _, kept, gone = dissolve_valence_two(sizes, flat, len(points))
    assert gone.tolist() == extra
    assert new_sizes.tolist() == [4] * 6  # every face is the cube's again; triangles at the vertex are dropped
    assert kept.sum() == 6 and kept[:6].all()
    surface, mesh = surface_from_file(obj(tmp_path / "split.obj", points, faces))
    report = check_surface(surface)
    assert mesh.dissolved_vertices.tolist() == extra
    assert report.boundary_edges == 0 and report.overshared_edges == 0 and report.max_normal_jump < 1e-12
    # what moves: the dissolved vertices no longer enter the surface, and their faces are the cube's,
    # so the surface is the plain cube's exactly (also where vertex 8 lay off the edge)
    cube, _ = surface_from_file(obj(tmp_path / "cube.obj", CUBE, CUBE_FACES))
    assert surface.n_patches == cube.n_patches
    assert np.allclose(sorted_coefficients(surface), sorted_coefficients(cube), rtol=0, atol=1e-14)


def test_a_face_listed_with_both_orientations_keeps_one_copy(tmp_path):
    path = obj(tmp_path / "card.obj", CUBE[:4], [[0, 1, 2, 3], [3, 2, 1, 0]])
    surface, mesh = surface_from_file(path)
    assert mesh.repeated_faces == 1 and mesh.n_faces == 1
    assert check_surface(surface).boundary_edges > 0  # one open square


def test_repeated_faces_are_dropped_and_the_cube_comes_back(tmp_path):
    faces = CUBE_FACES + [[5, 6, 7, 4], [4, 5, 6, 7]]  # the top face twice more, once rotated
    surface, mesh = surface_from_file(obj(tmp_path / "twice.obj", CUBE, faces))
    assert mesh.repeated_faces == 2
    cube, _ = surface_from_file(obj(tmp_path / "cube.obj", CUBE, CUBE_FACES))
    assert np.allclose(sorted_coefficients(surface), sorted_coefficients(cube), rtol=0, atol=1e-14)
    result = CliRunner().invoke(main, ["check", str(tmp_path / "twice.obj")])
    assert "dropped 2 faces that repeat an earlier face" in result.stderr and "G1: yes" in result.stdout


def test_a_reversed_copy_inside_a_surface_is_refused_with_its_lines(tmp_path):
    path = obj(tmp_path / "reversed.obj", CUBE, CUBE_FACES + [[7, 6, 5, 4]])  # the top face, reversed
    result = CliRunner().invoke(main, ["convert", str(path), "-o", str(tmp_path / "out.ply")])
    assert result.exit_code == 1
    assert "shared by 3 faces" in result.stderr and "faces on lines" in result.stderr and "15" in result.stderr


def test_repeated_faces_up_to_rotation_and_reversal_only():
    from c1surf.mesh.duplicate_faces import repeated_faces

    # a quad again (rotated), a crossed quad on the same vertices, a triangle and its reversal (a pillow)
    sizes = np.array([4, 4, 4, 3, 3])
    faces = np.concatenate([[0, 1, 2, 3], [2, 3, 0, 1], [0, 2, 1, 3], [4, 5, 6], [6, 5, 4]])
    assert repeated_faces(sizes, faces).tolist() == [False, True, False, False, True]
    # a reversed copy that is part of a surface (the two tent triangles of split_cube) stays
    points, tent, _ = split_cube("triangles")
    assert not repeated_faces(np.array([len(f) for f in tent]), np.concatenate(tent)).any()


def test_convert_notes_the_dissolved_vertices_and_creases_follow(tmp_path):
    points, faces, extra = split_cube("row")
    tags = "t crease 2/1/0 0 8 10\nt crease 2/1/0 8 9 10\nt crease 2/1/0 9 1 10\n"
    path = obj(tmp_path / "row.obj", points, faces, tags)
    result = CliRunner().invoke(main, ["convert", str(path), "-o", str(tmp_path / "out.obj"), "-r", "2"])
    assert result.exit_code == 0, result.output
    assert "dissolved 2 interior vertices of valence 2 into the edges they split (vertices 9, 10, as in the OBJ file" \
        in result.stderr
    creased, _ = surface_from_file(path)
    whole, _ = surface_from_file(obj(tmp_path / "cube.obj", CUBE, CUBE_FACES, "t crease 2/1/0 0 1 10\n"))
    assert np.allclose(sorted_coefficients(creased), sorted_coefficients(whole), rtol=0, atol=1e-14)
    corner = np.linalg.norm(tessellate_surface(creased, 8).points - [1, 0, 0], axis=1).min()
    smooth = np.linalg.norm(tessellate_surface(surface_from_file(path, ignore_tags=True)[0], 8).points - [1, 0, 0],
                            axis=1).min()
    assert corner < 0.2 * smooth  # the crease on 0-8-9-1 is the crease on 0-1


def test_collinear_corners_and_a_sliver_are_g1_and_finite(tmp_path):
    """A pentagon with three collinear corners (0, 8, 1) beside a thin triangle (8, 1, 5): nothing to repair."""
    points = list(CUBE) + [(1, 0, 0)]
    faces = [[0, 3, 2, 1, 8], CUBE_FACES[1], [0, 8, 5, 4], [8, 1, 5], CUBE_FACES[3], CUBE_FACES[4], CUBE_FACES[5]]
    surface, mesh = surface_from_file(obj(tmp_path / "collinear.obj", points, faces))
    assert mesh.dissolved_vertices.size == 0 and mesh.repeated_faces == 0
    report = check_surface(surface)
    assert report.boundary_edges == 0 and report.max_normal_jump < 1e-12
    tess = tessellate_surface(surface, 8)
    assert np.isfinite(tess.points).all() and np.isfinite(tess.normals).all()


def test_a_zero_area_face_whose_corners_all_have_valence_three_converts_g1_without_nan(tmp_path):
    """A triangular prism whose top triangle has collinear corners (zero area, every corner of valence 3):
    nothing to repair, so no note; the surface is closed and G1 and no output holds a NaN (normals and
    curvature included)."""
    from plyfile import PlyData

    points = [(0, 0, 0), (2, 0, 0), (1, 1.5, 0), (0, 0, 1), (1, 0, 1), (2, 0, 1)]
    faces = [[0, 2, 1], [3, 4, 5], [0, 1, 4, 3], [1, 2, 5, 4], [2, 0, 3, 5]]
    path = obj(tmp_path / "flat_top.obj", points, faces)
    out, patches = tmp_path / "out.ply", tmp_path / "out.json"
    result = CliRunner().invoke(main, ["convert", str(path), "-o", str(out), "--patches", str(patches), "--curvature"])
    assert result.exit_code == 0, result.output
    assert "note" not in result.stderr
    vertex = PlyData.read(str(out))["vertex"]
    assert all(np.isfinite(vertex[p.name]).all() for p in vertex.properties)
    surface, _ = surface_from_file(path)
    report = check_surface(surface)
    assert report.boundary_edges == 0 and report.max_normal_jump < 1e-12
    check = CliRunner().invoke(main, ["check", str(patches)])
    assert check.exit_code == 0 and "G1: yes" in check.output
