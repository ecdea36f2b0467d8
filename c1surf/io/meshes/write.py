"""Writing tessellated triangle meshes: the mesh to write, and the writer its suffix picks.

``TriangleMesh`` holds what a tessellation gives (points, triangles, normals)
and what may ride along per vertex (texture coordinates, colours, named
properties). ``write_mesh`` checks that the format keeps what the mesh carries
and calls the format's writer from ``io.registry.MESH_WRITERS``: OBJ and PLY
are c1surf's own vectorized writers (``obj_out``, ``ply_out``; float64 by
default, float32 on request), STL, GLB and OFF go through trimesh (STL and GLB
store float32 by definition). ``write_triangle_mesh`` and
``write_attribute_mesh`` are the shapes the commands hand over.
``write_streamed_mesh`` writes a tessellation given by blocks with the bytes
of these writers (``ply_out``, ``obj_out``, ``formats.stl_out``,
``formats.glb_out``: the last two copy trimesh's layout).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..finite import refuse_non_finite_mesh
from ..registry import MESH_WRITERS, suffix_of

# vertex colour properties as the readers name them (``prepare.extension_data`` carries them as point columns)
COLOUR_NAMES = ("red", "green", "blue", "alpha")

__all__ = ["TriangleMesh", "write_mesh", "write_streamed_mesh", "write_triangle_mesh", "write_attribute_mesh",
           "write_stl", "write_glb", "write_off"]


@dataclass
class TriangleMesh:
    """A triangle mesh to write, with optional per-vertex data.

    points : (V, 3) float
    triangles : (T, 3) int, 0-based
    normals : (V, 3) float or None, unit normals
    uv : (V, 2) float or None, texture coordinates (OBJ ``vt``, PLY ``s t``)
    colours : (V, c) float in [0, 1] or None, named by ``colour_names`` ("red", "green", "blue", "alpha")
    properties : dict name -> (V,) float or uint8, named scalars in order (PLY only; e.g. curvature and its colours)
    triangle_patch : (T,) int or None, the patch of each triangle (formats that hold "patch ids": USD)
    """

    points: np.ndarray
    triangles: np.ndarray
    normals: np.ndarray | None = None
    uv: np.ndarray | None = None
    colours: np.ndarray | None = None
    colour_names: tuple = ("red", "green", "blue")
    properties: dict = field(default_factory=dict)
    triangle_patch: np.ndarray | None = None

    @property
    def has_attributes(self) -> bool:
        """Whether texture coordinates or colours ride along (``convert --attributes``)."""
        return self.uv is not None or self.colours is not None


def write_mesh(path, mesh: TriangleMesh, suffix: str | None = None, float32: bool = False) -> None:
    """Write ``mesh`` in the format of ``suffix`` (default: the path's).

    Raises
    ------
    io.registry.UnsupportedFormat for a suffix c1surf does not write;
    ValueError when the format cannot keep what the mesh carries (attributes, properties)
    """
    suffix = suffix or suffix_of(path, MESH_WRITERS)
    fmt = MESH_WRITERS[suffix]
    if mesh.has_attributes and "attributes" not in fmt.holds:
        raise ValueError(f"texture coordinates and colours are written to {', '.join(MESH_WRITERS.holding('attributes'))} "
                         "files only")
    if mesh.properties and "properties" not in fmt.holds:
        raise ValueError(f"per-vertex properties need a {', '.join(MESH_WRITERS.holding('properties'))} output, not {suffix}")
    fmt.function(path, mesh, float32=float32)


def write_streamed_mesh(path, tessellation, suffix: str | None = None, float32: bool = False) -> None:
    """Write a tessellation given by blocks (``evaluation.stream.StreamedTessellation``), never held whole.

    The bytes are those ``write_triangle_mesh`` writes for the same tessellation
    with its normals. Raises ValueError for a format written whole only
    (``MESH_WRITERS.streamed()`` lists the others).
    """
    suffix = suffix or suffix_of(path, MESH_WRITERS)
    function = MESH_WRITERS[suffix].streamed_function
    if function is None:
        raise ValueError(f"{suffix} files are written whole, not by blocks ({', '.join(MESH_WRITERS.streamed())} are)")
    function(path, tessellation, float32=float32)


def write_triangle_mesh(path, points: np.ndarray, triangles: np.ndarray, normals: np.ndarray | None = None,
                        suffix: str | None = None, vertex_properties: dict | None = None,
                        vertex_colors: np.ndarray | None = None, float32: bool = False) -> None:
    """Write a triangle mesh; the format comes from ``suffix`` (default: the path's).

    Parameters
    ----------
    points : (V, 3) float (further columns are ignored)
    triangles : (T, 3) int
    normals : (V, 3) float or None, per-vertex unit normals
    vertex_properties : dict name -> (V,) float, or None: extra per-vertex scalars (PLY only)
    vertex_colors : (V, 3) uint8 or None, written as ``red green blue`` after them (PLY only)
    float32 : write coordinates and normals as float32 (PLY ``float``, fewer OBJ digits)
    """
    properties = dict(vertex_properties or {})
    if vertex_colors is not None:
        properties.update(zip(("red", "green", "blue"), np.asarray(vertex_colors, dtype=np.uint8).T))
    mesh = TriangleMesh(np.asarray(points)[:, :3], np.asarray(triangles), normals, properties=properties)
    write_mesh(path, mesh, suffix, float32)


def write_attribute_mesh(path, points, triangles, normals, attributes, names, *, colour_scale: float = 255.0,
                         **options) -> None:
    """Write a triangle mesh with texture coordinates and/or colours (``convert --attributes``).

    Parameters
    ----------
    points : (V, 3) float; triangles : (T, 3) int; normals : (V, 3) float or None
    attributes : (V, k) float, columns named by ``names`` ("u", "v", "red", "green", "blue", "alpha")
    colour_scale : 255 when colours are 0..255, 1 when 0..1
    **options : ``write_mesh``'s: suffix (".ply" or ".obj"; default: the path's), float32 (positions, normals and
        texture coordinates at float32 precision)
    """
    attributes, names = np.asarray(attributes, dtype=np.float64), list(names)
    uv = attributes[:, names.index("u") : names.index("u") + 2] if "u" in names else None
    picked = [k for k, name in enumerate(names) if name in COLOUR_NAMES]
    colours = np.clip(attributes[:, picked] / colour_scale, 0.0, 1.0) if picked else None
    mesh = TriangleMesh(np.asarray(points, dtype=np.float64)[:, :3], np.asarray(triangles, dtype=np.int64), normals,
                        uv=uv, colours=colours, colour_names=tuple(names[k] for k in picked))
    write_mesh(path, mesh, **options)


def _trimesh_export(path, mesh: TriangleMesh, file_type: str, **options) -> None:
    import trimesh  # imported here: only these formats need it

    refuse_non_finite_mesh(mesh, path, float32=file_type in ("stl", "glb"))  # float32 by definition

    shape = trimesh.Trimesh(vertices=mesh.points, faces=mesh.triangles, vertex_normals=mesh.normals, process=False,
                            validate=False)
    data = shape.export(file_type=file_type, **options)
    with open(path, "w" if isinstance(data, str) else "wb") as f:
        f.write(data)


def write_stl(path, mesh: TriangleMesh, float32: bool = False) -> None:
    """Binary STL through trimesh (float32 by definition; normals are per facet)."""
    _trimesh_export(path, mesh, "stl")


def write_glb(path, mesh: TriangleMesh, float32: bool = False) -> None:
    """Binary glTF through trimesh (float32 by definition)."""
    _trimesh_export(path, mesh, "glb")


def write_off(path, mesh: TriangleMesh, float32: bool = False) -> None:
    """OFF text through trimesh."""
    _trimesh_export(path, mesh, "off")
