"""Shading and reflection lines of a rendered ``image.Image``: arrays in, arrays out."""
from __future__ import annotations

import numpy as np

from .image import Image


def normals_of(image: Image) -> np.ndarray:
    """(H, W, 3) unit normal at each pixel (0 on the background)."""
    return np.stack([image.channels[f"N.{a}"] for a in "XYZ"], axis=-1)


def headlight(image: Image, ambient: float = 0.3) -> np.ndarray:
    """(H, W) diffuse shading from a light at the eye: ambient + (1 - ambient) |n . d|."""
    d = image.view_directions
    if d is None or not np.any(d):
        return np.ones(image.shape)
    lam = np.abs(np.einsum("hwd,hwd->hw", normals_of(image), d))
    return ambient + (1.0 - ambient) * np.nan_to_num(lam)


def reflection_phase(image: Image, axis=None) -> np.ndarray:
    """(H, W) angle in (-pi, pi] of the reflected view ray about the light-line ``axis``.

    The light is a set of parallel lines at infinity along ``axis`` (default: the
    camera's up vector), so the stripes ``sin(N phase)`` are the reflection lines of
    that environment; they are continuous where the normal is (G1) and break where
    it jumps. NaN on the background.
    """
    cam = image.camera
    axis = np.asarray(axis if axis is not None else cam.up, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    e1 = np.cross(cam.forward, axis)
    if np.linalg.norm(e1) < 1e-9:
        e1 = cam.right
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    d = image.view_directions
    n = normals_of(image)
    r = d - 2.0 * np.einsum("hwd,hwd->hw", d, n)[..., None] * n
    phase = np.arctan2(r @ e1, r @ e2)
    return np.where(image.mask, phase, np.nan)


def wrap(angle):
    """Angles into [-pi, pi)."""
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


def stripes(phase: np.ndarray, count: int = 12) -> np.ndarray:
    """(H, W) stripe intensity in [0, 1] from ``phase``: ``count`` black and white pairs per
    turn, antialiased by the phase change between neighbouring pixels. NaN stays NaN."""
    p = count * phase
    s = np.sin(p)
    gx = np.zeros_like(p)
    gy = np.zeros_like(p)
    dx = np.abs(wrap(p[:, 1:] - p[:, :-1]))
    dy = np.abs(wrap(p[1:, :] - p[:-1, :]))
    gx[:, :-1] = np.nan_to_num(dx)
    gy[:-1, :] = np.nan_to_num(dy)
    # sin(p) changes by about g per pixel near an edge of a stripe: a ramp one pixel wide,
    # and grey where the stripes are finer than the pixels.
    g = np.maximum(np.hypot(gx, gy), 1e-6)
    return np.clip(0.5 + 0.5 * s / g, 0.0, 1.0)
