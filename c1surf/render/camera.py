"""A pinhole or orthographic camera that frames a point set, and its pixel rays.

World axes: views are named for a Y-up scene (the OBJ convention): ``front``
looks along -Z, ``top`` down along -Y, ``side`` along -X, ``iso`` along
-(1, 1, 1). Pixel (row i, column j) has its centre at
``x = (2 (j + 0.5) / W - 1)``, ``y = 1 - 2 (i + 0.5) / H`` on the image plane.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# view name -> (direction from the target to the eye, up vector)
VIEWS = {
    "iso": ((1.0, 1.0, 1.0), (0.0, 1.0, 0.0)),
    "front": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    "back": ((0.0, 0.0, -1.0), (0.0, 1.0, 0.0)),
    "top": ((0.0, 1.0, 0.0), (0.0, 0.0, -1.0)),
    "bottom": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
    "side": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "left": ((-1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
}
PROJECTIONS = ("perspective", "orthographic")


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    length = np.linalg.norm(v)
    if not length > 0:
        raise ValueError("zero-length direction")
    return v / length


@dataclass(frozen=True)
class Camera:
    """eye : (3,), forward/right/up : (3,) orthonormal (right = forward x up),
    width, height : pixels; projection : "perspective" or "orthographic";
    tan_half_y : tan(fov_y / 2) (perspective) or half_height : half the image-plane
    height in world units (orthographic)."""

    eye: np.ndarray
    forward: np.ndarray
    right: np.ndarray
    up: np.ndarray
    width: int
    height: int
    projection: str
    tan_half_y: float = 0.0
    half_height: float = 0.0

    @property
    def aspect(self) -> float:
        return self.width / self.height

    def pixel_coordinates(self, rows: slice | None = None):
        """(n,) x, y image-plane coordinates in [-1, 1] of the pixel centres of ``rows``."""
        rows = rows or slice(0, self.height)
        i = np.arange(self.height)[rows]
        j = np.arange(self.width)
        x = (2.0 * (j + 0.5) / self.width - 1.0)[None, :].repeat(i.size, 0)
        y = (1.0 - 2.0 * (i + 0.5) / self.height)[:, None].repeat(self.width, 1)
        return x.ravel(), y.ravel()

    def rays(self, rows: slice | None = None):
        """Origins and unit directions, (n, 3) each, of the pixels in ``rows``
        (all rows by default), row-major."""
        x, y = self.pixel_coordinates(rows)
        if self.projection == "perspective":
            ty, tx = self.tan_half_y, self.tan_half_y * self.aspect
            d = self.forward + (x * tx)[:, None] * self.right + (y * ty)[:, None] * self.up
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            return np.broadcast_to(self.eye, d.shape).copy(), d
        hy, hx = self.half_height, self.half_height * self.aspect
        o = self.eye + (x * hx)[:, None] * self.right + (y * hy)[:, None] * self.up
        return o, np.broadcast_to(self.forward, o.shape).copy()

    def depth(self, points: np.ndarray) -> np.ndarray:
        """(n,) distance of ``points`` from the eye along the viewing direction."""
        return (np.asarray(points)[..., :3] - self.eye) @ self.forward

    def project(self, points: np.ndarray) -> np.ndarray:
        """(n, 2) float (row, column) pixel positions of ``points`` (centre of pixel = +0.5)."""
        rel = np.asarray(points)[..., :3] - self.eye
        x, y, z = rel @ self.right, rel @ self.up, rel @ self.forward
        if self.projection == "perspective":
            x = x / (z * self.tan_half_y * self.aspect)
            y = y / (z * self.tan_half_y)
        else:
            x = x / (self.half_height * self.aspect)
            y = y / self.half_height
        return np.stack([(1.0 - y) * self.height / 2.0, (x + 1.0) * self.width / 2.0], axis=-1)

    def attributes(self) -> dict:
        """EXR header attributes describing the camera."""
        out = {
            "c1surfProjection": self.projection,
            "c1surfEye": self.eye.astype(np.float32),
            "c1surfForward": self.forward.astype(np.float32),
            "c1surfUp": self.up.astype(np.float32),
        }
        if self.projection == "perspective":
            out["c1surfFovY"] = float(np.degrees(2 * np.arctan(self.tan_half_y)))
        else:
            out["c1surfHalfHeight"] = float(self.half_height)
        return out


def _frame(forward, up):
    forward = _unit(forward)
    up = np.asarray(up, dtype=np.float64)
    right = np.cross(forward, up)
    if np.linalg.norm(right) < 1e-9 * max(np.linalg.norm(up), 1e-300):
        # up parallel to the view: pick any perpendicular
        alt = np.array([0.0, 0.0, 1.0]) if abs(forward[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
        right = np.cross(forward, alt)
    right = _unit(right)
    return forward, right, np.cross(right, forward)


@dataclass(frozen=True)
class CameraPlacement:
    """Where a camera looks from and how it projects (``frame_camera`` frames the picture around it).

    view : a key of ``VIEWS``; ignored when ``eye`` is given
    eye, target, up : (3,) or None. ``target`` defaults to the centre of the bounding
        box. With ``eye``, a perspective camera stays there and its field of view
        frames everything unless ``fov`` is given; an orthographic one only takes the
        direction ``target - eye``.
    projection : "perspective" or "orthographic"
    fov : vertical field of view in degrees (perspective), default 30
    margin : fraction of empty border
    zoom : > 1 magnifies about the image centre (narrower field of view, same eye)
    """

    view: str = "iso"
    eye: tuple | None = None
    target: tuple | None = None
    up: tuple | None = None
    projection: str = "perspective"
    fov: float | None = None
    margin: float = 0.04
    zoom: float = 1.0


def frame_camera(points: np.ndarray, width: int, height: int, view: str = "iso", **placement) -> Camera:
    """A camera that shows all of ``points``.

    Parameters
    ----------
    points : (n, 3) float, what must be in the picture (e.g. tessellation vertices)
    width, height : int, pixels
    view, **placement : the fields of ``CameraPlacement`` (or ``placement=CameraPlacement(...)``)

    Returns
    -------
    Camera
    """
    given = placement.pop("placement", None)
    p = given if given is not None else CameraPlacement(view=view, **placement)
    view, eye, target, up, projection, fov, margin, zoom = (p.view, p.eye, p.target, p.up, p.projection, p.fov,
                                                           p.margin, p.zoom)
    if projection not in PROJECTIONS:
        raise ValueError(f"projection must be one of {PROJECTIONS}")
    pts = np.asarray(points, dtype=np.float64)[:, :3]
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre = 0.5 * (lo + hi) if target is None else np.asarray(target, dtype=np.float64)
    radius = max(0.5 * float(np.linalg.norm(hi - lo)), 1e-12)
    eye = None if eye is None else np.asarray(eye, dtype=np.float64)
    frame = _view_frame(centre, view, eye, up)
    fit = _Fit(pts, centre, radius, frame, width, height, 1.0 + margin)
    if projection == "orthographic":
        return fit.orthographic(zoom)
    if eye is None:
        return fit.perspective_from_afar(fov, zoom)
    return fit.perspective_at(eye, fov, zoom)


def _view_frame(centre: np.ndarray, view: str, eye, up):
    """(forward, right, up) looking from ``eye`` (or along the ``view``) at ``centre``."""
    if eye is not None:
        if not np.linalg.norm(centre - eye) > 0:
            raise ValueError(f"the eye {tuple(eye.tolist())} is the point looked at: move --eye or give another --target")
        return _frame(centre - eye, up if up is not None else (0.0, 1.0, 0.0))
    direction, default_up = VIEWS[view]
    return _frame(-_unit(direction), up if up is not None else default_up)


@dataclass(frozen=True)
class _Fit:
    """What a camera must frame: the points (n, 3), their centre and radius, the view frame, the image size
    and the border factor ``scale`` (1 + margin)."""

    points: np.ndarray
    centre: np.ndarray
    radius: float
    frame: tuple
    width: int
    height: int
    scale: float

    def _camera(self, eye, projection: str, **extent) -> Camera:
        forward, right, up = self.frame
        return Camera(eye, forward, right, up, self.width, self.height, projection, **extent)

    def _projected(self):
        """x, y, z : (n,) coordinates of the points relative to the centre, in the view frame."""
        forward, right, up = self.frame
        rel = self.points - self.centre
        return rel @ right, rel @ up, rel @ forward

    def orthographic(self, zoom: float) -> Camera:
        """Only the direction matters: the window centred on the projected extent, the ray origins in front of
        everything."""
        forward, right, up = self.frame
        x, y, z = self._projected()
        aspect = self.width / self.height
        cx, cy = 0.5 * (x.min() + x.max()), 0.5 * (y.min() + y.max())
        half = max(0.5 * (y.max() - y.min()), 0.5 * (x.max() - x.min()) / aspect, 1e-12 * self.radius) * self.scale
        eye = self.centre + cx * right + cy * up - forward * (float(np.max(-z)) + 0.1 * self.radius)
        return self._camera(eye, "orthographic", half_height=float(half / zoom))

    def perspective_from_afar(self, fov, zoom: float) -> Camera:
        """A field of view of ``fov`` degrees (default 30), the eye as near as framing everything allows."""
        x, y, z = self._projected()
        ty = np.tan(np.radians(fov if fov is not None else 30.0) / 2.0)
        tx = ty * self.width / self.height
        # Smallest distance d with |x| <= (d + z) tx / scale and |y| <= (d + z) ty / scale.
        d = max(float(np.max(np.abs(x) * self.scale / tx - z)), float(np.max(np.abs(y) * self.scale / ty - z)),
                float(np.max(-z)) + 1e-3 * self.radius)
        return self._camera(self.centre - d * self.frame[0], "perspective", tan_half_y=float(ty / zoom))

    def perspective_at(self, eye: np.ndarray, fov, zoom: float) -> Camera:
        """The eye where it is given; the field of view ``fov`` degrees, or the narrowest framing everything."""
        forward, right, up = self.frame
        if fov is not None:
            ty = np.tan(np.radians(fov) / 2.0)
        else:
            rel = self.points - eye
            depth = rel @ forward
            front = depth > 1e-9 * self.radius
            if not front.any():
                raise ValueError("the surface is behind the camera: move --eye or --target")
            ty = max(float(np.max(np.abs(rel[front] @ up) / depth[front])),
                     float(np.max(np.abs(rel[front] @ right) / depth[front])) / (self.width / self.height)) * self.scale
            ty = min(ty, np.tan(np.radians(150.0) / 2.0))
        return self._camera(eye, "perspective", tan_half_y=float(ty / zoom))
