"""Write USD: the fit's control mesh as a SubD cage with its creases, corners and holes (``write_usd_cage``,
``fit --cage cage.usda``) and a tessellation (``write_usd``, ``-o smooth.usd``), through usd-core.

Both are one ``UsdGeom.Mesh`` prim, the stage's default prim, Z up, ``metersPerUnit`` 1 (the numbers as they are:
a stage without it is in centimetres, which Blender imports scaled by 0.01). USD stores points as float32 (``point3f[]``): the
float64 positions ride along in ``primvars:c1surf:points`` (``double3[]``, vertex interpolation), which c1surf's
reader takes wherever they round to the float points, so that ``c1surf convert cage.usda`` rebuilds the fitted
surface bit for bit while any other reader sees the float points. ``.usda`` is text, ``.usd`` and ``.usdc`` crate
(binary); the layer is built in memory and exported, so nothing is written before it is whole.
"""
from __future__ import annotations

import numpy as np

from ...finite import refuse_non_finite, refuse_non_finite_mesh
from .stage import PATCH_PRIMVAR, POINTS_PRIMVAR, SHARPNESS_ATTRIBUTES, pxr_modules

__all__ = ["write_usd_cage", "write_usd"]


def write_usd_cage(path, points, face_sizes, face_vertices, features=None, comments=()) -> None:
    """Write a polygon control mesh as a USD SubD cage (``subdivisionScheme = "catmullClark"``, the scheme DCC
    tools preview a cage with) with its tags: ``creaseIndices``/``creaseLengths`` one crease of 2 vertices per crease
    edge with its ``creaseSharpnesses``, ``cornerIndices``/``cornerSharpnesses``, ``holeIndices`` (indices from 0, as
    in the mesh; sharpness as c1surf keeps it: 10 infinitely sharp, as USD and OpenSubdiv read it).

    Parameters
    ----------
    path : str or os.PathLike, .usda (text), .usd or .usdc (crate)
    points : (V, 3) float; face_sizes : (F,) int; face_vertices : (sum(face_sizes),) int, 0-based
    features : a ``construction.features.SharpFeatures`` (``crease_edges`` (E, 2), ``crease_sharpness`` (E,),
        ``corner_vertices`` (C,), ``corner_sharpness`` (C,), ``hole_faces`` (H,)), or None
    comments : lines of the layer's ``doc`` (``fit --cage``: the ``convert`` command that rebuilds the fit first)
    """
    points = np.asarray(points, dtype=np.float64)[:, :3]
    refuse_non_finite(points, "cage points", path, np.float32)
    stage, mesh = _stage_with_mesh(path, "cage", comments)
    _geometry(mesh, points, np.asarray(face_sizes), np.asarray(face_vertices), doubles=True)
    mesh.CreateSubdivisionSchemeAttr("catmullClark")
    if features is not None:
        _tags(mesh, features, path)
    _export(stage, path)


def write_usd(path, mesh, float32: bool = False) -> None:
    """Write a tessellation (an ``io.meshes.write.TriangleMesh``) as a USD polygon mesh (``subdivisionScheme =
    "none"``): points, vertex normals, triangles counter-clockwise from outside (``rightHanded``), the patch of each
    triangle as ``primvars:c1surf:patch`` (uniform) when the mesh carries it, and the float64 positions as
    ``primvars:c1surf:points`` unless ``float32``."""
    refuse_non_finite_mesh(mesh, path, float32=True)
    stage, prim = _stage_with_mesh(path, "surface", ["c1surf: smooth surface (tessellated Bezier patches)"])
    triangles = np.asarray(mesh.triangles)
    _geometry(prim, np.asarray(mesh.points, dtype=np.float64)[:, :3], np.full(len(triangles), 3), triangles.ravel(),
              doubles=not float32)
    prim.CreateSubdivisionSchemeAttr("none")
    _, UsdGeom, Sdf, Vt, _ = pxr_modules(path, writing=True)
    if mesh.normals is not None:
        normals = np.nan_to_num(np.asarray(mesh.normals, dtype=np.float64)[:, :3])
        prim.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(normals.astype(np.float32)))
        prim.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
    patch = getattr(mesh, "triangle_patch", None)
    if patch is not None:
        primvar = UsdGeom.PrimvarsAPI(prim).CreatePrimvar(PATCH_PRIMVAR, Sdf.ValueTypeNames.IntArray,
                                                          UsdGeom.Tokens.uniform)
        primvar.Set(Vt.IntArray.FromNumpy(np.asarray(patch, dtype=np.int32)))
    _export(stage, path)


def _stage_with_mesh(path, name: str, comments):
    """(an in-memory stage, Z up, its default prim ``/name``: a UsdGeom.Mesh), the layer's doc ``comments``."""
    Usd, UsdGeom, _, _, _ = pxr_modules(path, writing=True)
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)  # unset, USD means centimetres: Blender would scale the mesh by 0.01
    mesh = UsdGeom.Mesh.Define(stage, "/" + name)
    stage.SetDefaultPrim(mesh.GetPrim())
    if comments:
        stage.GetRootLayer().documentation = "\n".join(comments)
    return stage, mesh


def _geometry(mesh, points: np.ndarray, sizes: np.ndarray, corners: np.ndarray, doubles: bool) -> None:
    """Points (float32; the float64 ones as ``primvars:c1surf:points`` when ``doubles``), faces, extent."""
    _, UsdGeom, Sdf, Vt, _ = pxr_modules("", writing=True)
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points.astype(np.float32)))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(sizes.astype(np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(corners.astype(np.int32)))
    mesh.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
    low, high = (points.min(axis=0), points.max(axis=0)) if len(points) else (np.zeros(3), np.zeros(3))
    mesh.CreateExtentAttr(Vt.Vec3fArray.FromNumpy(np.stack([low, high]).astype(np.float32)))
    if doubles:
        primvar = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(POINTS_PRIMVAR, Sdf.ValueTypeNames.Double3Array,
                                                          UsdGeom.Tokens.vertex)
        primvar.Set(Vt.Vec3dArray.FromNumpy(np.ascontiguousarray(points)))


def _tags(mesh, features, path) -> None:
    """The crease, corner and hole attributes of ``features`` (authored only where there are some)."""
    _, _, _, Vt, _ = pxr_modules(path, writing=True)
    edges = np.asarray(features.crease_edges, dtype=np.int64).reshape(-1, 2)
    sharpness = np.asarray(features.crease_sharpness, dtype=np.float64)
    corners, corner_sharpness = np.asarray(features.corner_vertices), np.asarray(features.corner_sharpness)
    holes = np.asarray(features.hole_faces, dtype=np.int64).ravel()
    refuse_non_finite(np.r_[sharpness, corner_sharpness], "sharpness values", path, np.float32)
    if len(edges):
        mesh.CreateCreaseIndicesAttr(Vt.IntArray.FromNumpy(edges.ravel().astype(np.int32)))
        mesh.CreateCreaseLengthsAttr(Vt.IntArray.FromNumpy(np.full(len(edges), 2, dtype=np.int32)))
        mesh.CreateCreaseSharpnessesAttr(Vt.FloatArray.FromNumpy(sharpness.astype(np.float32)))
        _exact_sharpness(mesh, "crease", sharpness)
    if len(corners):
        mesh.CreateCornerIndicesAttr(Vt.IntArray.FromNumpy(corners.astype(np.int32)))
        mesh.CreateCornerSharpnessesAttr(Vt.FloatArray.FromNumpy(corner_sharpness.astype(np.float32)))
        _exact_sharpness(mesh, "corner", corner_sharpness)
    if holes.size:
        mesh.CreateHoleIndicesAttr(Vt.IntArray.FromNumpy(holes.astype(np.int32)))


def _exact_sharpness(mesh, kind: str, values: np.ndarray) -> None:
    """The float64 sharpness in c1surf's own attribute (``SHARPNESS_ATTRIBUTES``) where float32 does not hold it."""
    values = np.asarray(values, dtype=np.float64)
    if np.array_equal(values.astype(np.float32).astype(np.float64), values):
        return  # 10 (infinitely sharp), 2.5, ...: the float attribute holds them
    _, _, Sdf, Vt, _ = pxr_modules("", writing=True)
    attr = mesh.GetPrim().CreateAttribute(SHARPNESS_ATTRIBUTES[kind], Sdf.ValueTypeNames.DoubleArray, custom=True)
    attr.Set(Vt.DoubleArray.FromNumpy(values))


def _export(stage, path) -> None:
    """The stage's layer written to ``path`` in the format of its suffix (text or crate)."""
    from ...errors import OutputError

    if not stage.GetRootLayer().Export(str(path)):
        raise OutputError(path, "usd-core could not write the file: check the folder and the free space")
