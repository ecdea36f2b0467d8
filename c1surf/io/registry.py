"""Which file formats c1surf reads and writes: one suffix table per kind of file.

Each table maps a lower-case suffix to a :class:`Format`: the function that
reads or writes it and one line saying what the file holds. The command line
takes its suffix checks (:func:`suffix_of`) and its help texts
(:func:`suffix_list`) from here, and the dispatching readers and writers
(``io.meshes.read.read_mesh``, ``io.meshes.write.write_mesh``,
``io.patches.formats``) their functions. To add a format, write its reader or
writer in ``io/meshes`` (readers beyond OBJ and PLY: ``io/meshes/formats``),
``io/patches`` or ``io/images`` and add one line here.

Functions are named as ``"module:function"`` and imported on first use, so that
checking a suffix (or ``c1surf --help``) loads none of the format libraries
(trimesh, plyfile, Open CASCADE), and so that the format modules, which use
this registry to dispatch, are not imported by it in turn.

Signatures, by table:

- ``MESH_READERS``: ``read(path, *, keep_degenerate=False) -> io.meshes.mesh_file.MeshFile`` (keep_degenerate:
  faces that repeat a vertex kept as written, for ``c1surf inspect``)
- ``MESH_WRITERS``: ``write(path, mesh: io.meshes.write.TriangleMesh, float32=False)``
- ``PATCH_READERS``: ``read(path) -> evaluation.patch_set.PatchSet``
- ``PATCH_WRITERS``: ``write(path, patch_set, *, file_name=None, units="mm", group=True)``
  (options a format has no use for are ignored)
- ``CAGE_WRITERS``: ``write(path, points, face_sizes, face_vertices, features=None, comments=())``, the fit's
  control mesh with its tags (``fit --cage``)
- ``IMAGE_WRITERS``: the image files of ``c1surf render`` (each writer takes its own picture type)
"""
from __future__ import annotations

import importlib
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from .errors import C1SurfFileError

__all__ = ["Format", "FormatTable", "UnsupportedFormat", "suffix_of", "suffix_list", "MESH_READERS", "MESH_WRITERS",
           "PATCH_READERS", "PATCH_WRITERS", "IMAGE_WRITERS", "CAGE_WRITERS"]


@dataclass(frozen=True)
class Format:
    """One file format of a table.

    suffixes : tuple of str, lower case with the dot (".igs", ".iges"): the first is the usual one
    target : str, "module:function" of the reader or writer
    description : str, what the file holds, in a few words
    holds : frozenset of str, optional per-vertex data the format keeps (mesh writers):
        "attributes" (texture coordinates and colours), "properties" (named scalars, e.g. curvature)
    streamed : str, "module:function" of a writer by blocks that writes the bytes of the whole-data writer:
        a mesh writer taking the tessellation (``write(path, tessellation, float32=False)``,
        ``evaluation.stream.StreamedTessellation``), a patch writer taking the patches
        (``write(path, stream, **options)``, ``evaluation.patch_set.PatchStream``); "" if written whole only
    file_bytes : tuple of int, the bytes a written file takes (a little above what was measured, for the disk
        guard): mesh writers (per vertex, per triangle) with float64 positions and normals; patch writers
        (per coefficient row: 9 per biquadratic and 16 per bicubic patch, unmerged: merging only shrinks them)
    float32 : bool, mesh writers: ``--float32`` halves the bytes per vertex
    held_points : bool, streamed mesh writers that hold the positions of the vertices on patch sides and corners
        (float64 x, y, z; at -r 2 every vertex): STL's records need each triangle's corners
    scratch_bytes : int, bytes per vertex a streamed mesh writer keeps on the disk beside its output while writing
        (the vertex blocks of OBJ and GLB, evaluated once and read back: 6 float64)
    merged : bool, patch writers: merged B-spline pieces by default (CAD opens few large faces: IGES, STEP)
    memory : (base, per patch) bytes, the peak memory a patch writer takes beyond the patch set it is
        given, measured (``/usr/bin/time -v``, see ``writer_memory``); (0, 0) where it is small beside the patches
    """

    suffixes: tuple
    target: str
    description: str
    holds: frozenset = field(default_factory=frozenset)
    streamed: str = ""
    file_bytes: tuple = ()
    float32: bool = False
    held_points: bool = False
    scratch_bytes: int = 0
    merged: bool = False
    memory: tuple = (0, 0)

    def writer_memory(self, n_patches: int) -> int:
        """Bytes of memory the writer needs at its peak for a surface of ``n_patches`` patches (an upper estimate:
        every patch its own face, as ``--no-merge`` writes them; packed files take less)."""
        base, per_patch = self.memory
        return int(base + per_patch * n_patches) if per_patch else 0

    @property
    def function(self):
        """The reader or writer (its module is imported on first use)."""
        return _resolve(self.target)

    @property
    def streamed_function(self):
        """The writer by blocks (``streamed``), or None."""
        return _resolve(self.streamed) if self.streamed else None


def _resolve(target: str):
    module, name = target.split(":")
    return getattr(importlib.import_module(module), name)


class FormatTable(Mapping):
    """Suffix -> Format of one kind of file, in the order the formats were listed.

    noun : str, what a file of this kind is ("mesh format"), for messages
    verb : str, what c1surf does with it ("reads", "writes")
    """

    def __init__(self, noun: str, verb: str, formats: list[Format]):
        self.noun, self.verb = noun, verb
        self._formats = {suffix: f for f in formats for suffix in f.suffixes}

    def __getitem__(self, suffix: str) -> Format:
        return self._formats[suffix]

    def __iter__(self):
        return iter(self._formats)

    def __len__(self) -> int:
        return len(self._formats)

    def holding(self, data: str) -> tuple:
        """Suffixes of the formats that keep ``data`` ("attributes", "properties")."""
        return tuple(s for s, f in self._formats.items() if data in f.holds)

    def streamed(self) -> tuple:
        """Suffixes of the formats written by blocks (``Format.streamed``)."""
        return tuple(s for s, f in self._formats.items() if f.streamed)

    def names(self) -> str:
        """The formats for help texts, one name each (the longest suffix), in table order: "OBJ, PLY, STL, OFF"."""
        return ", ".join(dict.fromkeys(_name(f.suffixes).lstrip(".").upper() for f in self._formats.values()))


def _name(suffixes: tuple) -> str:
    """The suffix that names a format: the longest (IGES, STEP), or the first where it begins every other (USD)."""
    if all(s.startswith(suffixes[0]) for s in suffixes):
        return suffixes[0]
    return max(suffixes, key=len)


class UnsupportedFormat(C1SurfFileError, ValueError):
    """A path whose suffix names no format of the table it was checked against."""


def suffix_list(table: Mapping) -> str:
    """The suffixes of a table, sorted, for messages and help texts: ".glb, .obj, .off"."""
    return ", ".join(sorted(table))


def suffix_of(path, table: Mapping) -> str:
    """Lower-case suffix of ``path`` if ``table`` has a format for it.

    Parameters
    ----------
    path : str or os.PathLike
    table : FormatTable (or any mapping keyed by suffix)

    Returns
    -------
    str, e.g. ".ply" (also for "MESH.PLY")

    Raises
    ------
    UnsupportedFormat
        ``PATH: unsupported mesh format (suffix '.stl'): c1surf reads .obj, .ply files``
    """
    path = os.fspath(path)
    suffix = Path(path).suffix
    if suffix.lower() in table:
        return suffix.lower()
    shown = f"suffix {suffix!r}" if suffix else "no suffix"
    noun, verb = getattr(table, "noun", "file format"), getattr(table, "verb", "handles")
    raise UnsupportedFormat(path, f"unsupported {noun} ({shown}): c1surf {verb} {suffix_list(table)} files")


_MESHES, _PATCHES, _IMAGES = "c1surf.io.meshes.", "c1surf.io.patches.", "c1surf.io.images."
# Peak memory of the CAD writers: (base, bytes per patch), the whole process's peak (/usr/bin/time -v) writing a
# patch set read from NPZ, torus (1,536 patches), penguin (3,360) and fandisk (12,224), packed and --no-merge, the
# larger of the two (--no-merge: one face per patch). STEP 456-605 MB for the first two (61 KB a patch more
# with --no-merge, 47 KB packed; 840 MB packed fandisk); IGES 85-136 MB (10 KB a patch with --no-merge, 4 KB packed).
# Open CASCADE's libraries take about 290 MB on their own (363 MB with Python, numpy and the patch set).
IGES_MEMORY = (80 << 20, 10_000)
STEP_MEMORY = (400 << 20, 62_000)
_BOTH = frozenset({"attributes", "properties"})

MESH_READERS = FormatTable("mesh format", "reads", [
    Format((".obj",), _MESHES + "obj:read_obj", "Wavefront OBJ: polygons of any size, vt/vn, v x y z w weights, groups"),
    Format((".ply",), _MESHES + "ply:read_ply", "PLY (ASCII or binary): polygons, normals, uv, weight, blend, colours"),
    Format((".stl",), _MESHES + "formats.stl:read_stl", "STL (ASCII or binary, through trimesh): triangles, welded"),
    Format((".off",), _MESHES + "formats.off:read_off", "OFF text (also COFF, NOFF): polygons of any size"),
    Format((".usd", ".usda", ".usdc", ".usdz"), _MESHES + "usd.read:read_usd",
           "USD (usd-core, the usd extra): UsdGeom.Mesh prims with creases, corners, holes"),
])

# file_bytes measured on twisted.obj (15,682 vertices, 31,360 triangles at -r 8; 3,636 coefficient rows), a little
# above; the IGES B-rep takes 273 bytes a row on twisted, 318 on spot.
MESH_WRITERS = FormatTable("mesh format", "writes", [
    Format((".obj",), _MESHES + "obj_out:write_obj", "Wavefront OBJ text: v, vt, vn, f", frozenset({"attributes"}),
           streamed=_MESHES + "obj_out:write_obj_stream", file_bytes=(95, 50), float32=True, scratch_bytes=48),
    Format((".ply",), _MESHES + "ply_out:write_ply", "binary PLY: positions, normals, any per-vertex properties", _BOTH,
           streamed=_MESHES + "ply_out:write_ply_stream", file_bytes=(48, 13), float32=True),
    Format((".stl",), _MESHES + "write:write_stl", "binary STL (float32, through trimesh)",
           streamed=_MESHES + "formats.stl_out:write_stl_stream", file_bytes=(0, 50), held_points=True),
    Format((".glb",), _MESHES + "write:write_glb", "binary glTF (float32, through trimesh)",
           streamed=_MESHES + "formats.glb_out:write_glb_stream", file_bytes=(24, 12), scratch_bytes=48),
    Format((".off",), _MESHES + "write:write_off", "OFF text (through trimesh)", file_bytes=(45, 20)),
    Format((".usd", ".usdc"), _MESHES + "usd.write:write_usd", "USD crate (usd-core): points, normals, patch of each "
           "triangle, float64 points", frozenset({"patch ids"}), file_bytes=(56, 20), float32=True),
    Format((".usda",), _MESHES + "usd.write:write_usd", "USD text (usd-core): points, normals, patch of each triangle, "
           "float64 points", frozenset({"patch ids"}), file_bytes=(150, 40), float32=True),
])

# The fit's control mesh with its sharp features (``fit --cage``):
# ``write(path, points, face_sizes, face_vertices, features=None, comments=())``.
CAGE_WRITERS = FormatTable("cage format", "writes", [
    Format((".obj",), _MESHES + "obj_out:write_cage", "OBJ with OpenSubdiv `t` crease, corner and hole lines"),
    Format((".usda", ".usd", ".usdc"), _MESHES + "usd.write:write_usd_cage",
           "USD UsdGeom.Mesh (usd-core) with its creases, corners and holes, float64 points kept"),
])

PATCH_READERS = FormatTable("patch format", "reads", [
    Format((".json",), _PATCHES + "json_patches:read_patch_set_json", "c1surf patch file as JSON (docs/patch-format.md)"),
    Format((".npz",), _PATCHES + "npz:read_patch_set_npz", "c1surf patch file as NumPy arrays"),
    Format((".igs", ".iges"), _PATCHES + "iges:read_patch_set_iges", "IGES 5.3 Bezier patches and merged B-splines"),
    Format((".step", ".stp"), _PATCHES + "step:read_patch_set_step", "STEP Bezier and merged B-spline faces (Open CASCADE)"),
])

PATCH_WRITERS = FormatTable("patch format", "writes", [
    Format((".json",), _PATCHES + "json_patches:write_patch_set_json", "c1surf patch file as JSON (docs/patch-format.md)",
           streamed=_PATCHES + "json_patches:write_patch_stream_json", file_bytes=(80,)),
    Format((".npz",), _PATCHES + "npz:write_patch_set_npz", "c1surf patch file as NumPy arrays",
           streamed=_PATCHES + "npz:write_patch_stream_npz", file_bytes=(45,)),
    Format((".igs", ".iges"), _PATCHES + "iges:write_patch_set_iges", "IGES 5.3 rational B-spline surfaces (type 128)",
           file_bytes=(330,), merged=True, memory=IGES_MEMORY),
    Format((".step", ".stp"), _PATCHES + "step:write_patch_set_step", "STEP AP214 faces, sewn (Open CASCADE)",
           file_bytes=(460,), merged=True, memory=STEP_MEMORY),
])

IMAGE_WRITERS = FormatTable("image format", "writes", [
    Format((".exr",), _IMAGES + "exr:write_exr", "OpenEXR: float32 channels (colour, depth, normals, curvature)"),
    Format((".png",), _IMAGES + "png:write_png", "PNG preview (8-bit sRGB)"),
])
