"""``InputOptions``: how a mesh file becomes the construction's input (beside ``SurfaceOptions``: how it is shaped)."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

from ..errors import OptionError

__all__ = ["InputOptions", "NON_MANIFOLD_RULES"]

NON_MANIFOLD_RULES = ("sheets", "refuse")


@dataclass(frozen=True)
class InputOptions:
    """What to read from a mesh file besides its polygons, and how to repair it (``prepare.pipeline``).

    weld : float in [0, 1] or None, welding tolerance relative to the bounding-box diagonal (0: equal
        positions only, the default), None: keep the file's vertices
    blend_file : path of a sidecar JSON of per-cell / per-vertex blend ratios, or None (PLY ``blend``
        properties are always used)
    weights : None (use the file's vertex weights when some differ from 1), True or False: rational patches (A2a)
    normals : interpolate the file's vertex normals (A1a; implies ``SurfaceOptions.interpolate_vertices``)
    attributes : carry texture coordinates and colours as extra point columns
    creases_file : path of a sidecar JSON of creases, corners and holes, or None (the file's own tags are
        always used unless ``ignore_tags``)
    crease_angle : degrees in [0, 180), or None: edges with a larger dihedral angle become infinitely sharp creases
    ignore_tags : build the smooth surface: the file's sharp-feature tags are read and named in a note, not used
    non_manifold : "sheets" (edges in more than two faces cut into manifold sheets meeting along a C0 crease,
        with exact creases) or "refuse"
    exact_creases : True (infinitely sharp creases as C0 seams), False (the sharpest G1 crease), or None, the
        one default: C0 seams unless vertices are interpolated (A1a takes no C0 seams yet). ``surface_options``
        resolves it into ``SurfaceOptions.exact_creases``, the construction's own switch.
    usd : ``io.meshes.usd.stage.UsdReadOptions`` or None (the reader's defaults): which meshes of a USD file, and
        where (passed to the reader as it is)
    """

    weld: float | None = 0.0
    blend_file: object = None
    weights: bool | None = None
    normals: bool = False
    attributes: bool = False
    creases_file: object = None
    crease_angle: float | None = None
    ignore_tags: bool = False
    non_manifold: str = "sheets"
    exact_creases: bool | None = None
    usd: object = None

    def check(self) -> "InputOptions":
        """Raise OptionError (a ValueError) for a value the preparation cannot take; else return self."""
        if self.weld is not None and not (math.isfinite(self.weld) and 0.0 <= self.weld <= 1.0):
            raise OptionError(f"the welding tolerance must be a number in [0, 1], got {self.weld}")
        if self.crease_angle is not None and not (math.isfinite(self.crease_angle) and 0.0 <= self.crease_angle < 180.0):
            raise OptionError(f"the crease angle must be a number of degrees in [0, 180), got {self.crease_angle}")
        if self.non_manifold not in NON_MANIFOLD_RULES:
            raise OptionError(f"non_manifold must be one of {NON_MANIFOLD_RULES}")
        return self

    def surface_options(self, options):
        """``options`` (a ``SurfaceOptions``) as these inputs build it: vertex interpolation when the normals are
        interpolated, and ``exact_creases`` resolved (``InputOptions.exact_creases``)."""
        interpolate = options.interpolate_vertices or self.normals
        exact = (not interpolate) if self.exact_creases is None else bool(self.exact_creases)
        return replace(options, interpolate_vertices=interpolate, exact_creases=exact)
