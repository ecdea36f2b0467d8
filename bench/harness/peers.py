"""The subdivision libraries a user would pick instead of c1surf, each as its user would run it.

Each peer reads the OBJ with its own reader (pyOpenSubdiv has none: the
harness's plain reader), subdivides, and writes a binary PLY with its own
writer (pyOpenSubdiv: the harness's). Catmull-Clark peers take the polygons;
Loop peers the triangles their reader makes (a fan per polygon).
"""
from __future__ import annotations

import numpy as np

from .meshes import fan_triangles, read_polygon_obj, write_ply


class Peer:
    """One library: ``read(path)``, ``subdivide(mesh, levels)``, ``write(mesh, path)``, ``arrays(mesh)``."""

    name = label = module = scheme = ""

    def arrays(self, mesh) -> tuple[np.ndarray, np.ndarray]:
        """(points (V, 3), triangles (T, 3)) of a subdivided mesh."""
        return np.asarray(mesh[0], dtype=np.float64), np.asarray(mesh[1], dtype=np.int64)


class PyMeshLab(Peer):
    name, label, module, scheme = "pymeshlab", "pymeshlab Catmull-Clark", "pymeshlab", "Catmull-Clark"

    def read(self, path):
        import pymeshlab

        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(path))  # polygons kept as faux-edge triangle fans, as MeshLab does
        return ms

    def subdivide(self, ms, levels):
        ms.meshing_surface_subdivision_catmull_clark(iterations=levels)
        return ms

    def write(self, ms, path):
        ms.save_current_mesh(str(path), binary=True)

    def arrays(self, ms):
        m = ms.current_mesh()
        return super().arrays((m.vertex_matrix(), m.face_matrix()))


class PyOpenSubdiv(Peer):
    name, label, module, scheme = "pyopensubdiv", "pyOpenSubdiv Catmull-Clark", "pyOpenSubdiv.pysubdivision", "Catmull-Clark"

    def read(self, path):
        return read_polygon_obj(path)

    def subdivide(self, mesh, levels):
        from pyOpenSubdiv.pysubdivision import pysubdivide

        points, sizes, corners = mesh
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        faces = [corners[a:b].tolist() for a, b in zip(offsets[:-1], offsets[1:])]
        result = pysubdivide(levels, points.tolist(), faces, corners.tolist(), sizes.tolist())
        return np.array(result["vertices"], dtype=np.float64), np.array(result["faces"], dtype=np.int64)

    def write(self, mesh, path):
        write_ply(path, *mesh)

    def arrays(self, mesh):
        points, quads = mesh
        return points, fan_triangles(np.full(len(quads), quads.shape[1]), quads.ravel())


class Libigl(Peer):
    name, label, module, scheme = "igl", "libigl Loop", "igl", "Loop"

    def read(self, path):
        import igl

        return igl.read_triangle_mesh(str(path))

    def subdivide(self, mesh, levels):
        import igl

        return igl.loop(*mesh, levels)

    def write(self, mesh, path):
        import igl

        igl.write_triangle_mesh(str(path), *mesh, igl.FileEncoding.Binary)


class Trimesh(Peer):
    name, label, module, scheme = "trimesh", "trimesh Loop", "trimesh.remesh", "Loop"

    def read(self, path):
        import trimesh

        mesh = trimesh.load(str(path), process=False, force="mesh", maintain_order=True)  # no splits at UV seams
        return np.asarray(mesh.vertices), np.asarray(mesh.faces)

    def subdivide(self, mesh, levels):
        import trimesh.remesh

        return trimesh.remesh.subdivide_loop(*mesh, iterations=levels)

    def write(self, mesh, path):
        import trimesh

        trimesh.Trimesh(*mesh, process=False).export(str(path), file_type="ply", encoding="binary")


PEERS = {peer.name: peer for peer in (PyMeshLab(), PyOpenSubdiv(), Libigl(), Trimesh())}
