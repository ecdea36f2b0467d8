"""Pictures for people: colour maps, shaded curvature previews with a colour bar,
stripe (zebra) images. Pictures are (H, W, 3) uint8 sRGB arrays; ``io.images.png``
writes them.

Colour maps are small numpy tables (no matplotlib): ``gray`` is the black-to-white
ramp of the paper's curvature figures, ``viridis`` a perceptually uniform map
(matplotlib's, sampled at 33 entries and interpolated; within 2.5/255 of it).
"""
from __future__ import annotations

import numpy as np

from .shading import headlight, reflection_phase, stripes

__all__ = ["COLORMAPS", "SIGNED", "colormap", "curvature_range", "preview_rgb", "add_colorbar", "srgb_to_linear",
           "rgb8", "curvature_picture", "zebra_picture"]

_VIRIDIS = np.array([
    (0.2670, 0.0049, 0.3294), (0.2770, 0.0503, 0.3757), (0.2823, 0.0950, 0.4173), (0.2829, 0.1359, 0.4534),
    (0.2788, 0.1755, 0.4834), (0.2706, 0.2141, 0.5071), (0.2590, 0.2515, 0.5247), (0.2450, 0.2877, 0.5373),
    (0.2297, 0.3224, 0.5457), (0.2143, 0.3556, 0.5512), (0.1994, 0.3876, 0.5546), (0.1856, 0.4186, 0.5568),
    (0.1727, 0.4488, 0.5579), (0.1607, 0.4785, 0.5581), (0.1490, 0.5081, 0.5573), (0.1378, 0.5375, 0.5549),
    (0.1276, 0.5669, 0.5506), (0.1206, 0.5964, 0.5436), (0.1206, 0.6258, 0.5335), (0.1323, 0.6550, 0.5197),
    (0.1579, 0.6838, 0.5017), (0.1966, 0.7118, 0.4792), (0.2461, 0.7389, 0.4520), (0.3041, 0.7647, 0.4199),
    (0.3692, 0.7889, 0.3829), (0.4401, 0.8111, 0.3410), (0.5160, 0.8312, 0.2943), (0.5958, 0.8487, 0.2433),
    (0.6785, 0.8637, 0.1895), (0.7624, 0.8764, 0.1371), (0.8456, 0.8873, 0.0997), (0.9261, 0.8973, 0.1041),
    (0.9932, 0.9062, 0.1439),
])
COLORMAPS = {"viridis": _VIRIDIS, "gray": np.array([(0.0, 0.0, 0.0), (1.0, 1.0, 1.0)])}
BACKGROUND = (0.82, 0.83, 0.85)  # sRGB, light grey
SIGNED = {"kmax": False, "K": True, "H": True, "k1": True, "k2": True}  # signed: colour range symmetric about 0


def colormap(values: np.ndarray, lo: float, hi: float, name: str = "viridis") -> np.ndarray:
    """(..., 3) sRGB in [0, 1]: ``values`` mapped linearly from [lo, hi] (clamped); NaN -> 0."""
    table = COLORMAPS[name]
    span = hi - lo if hi > lo else 1.0
    t = np.clip((np.nan_to_num(np.asarray(values, dtype=np.float64)) - lo) / span, 0.0, 1.0)
    x = np.linspace(0.0, 1.0, table.shape[0])
    return np.stack([np.interp(t, x, table[:, k]) for k in range(3)], axis=-1)


def curvature_range(values: np.ndarray, signed: bool, percentile: float = 98.0) -> tuple[float, float]:
    """Robust colour range: [0, p] (or [-p, p] for signed quantities), p the
    ``percentile`` of |values| over finite entries, so a few sharp spots do not
    wash out the rest."""
    v = np.abs(values[np.isfinite(values)])
    top = float(np.percentile(v, percentile)) if v.size else 1.0
    if not top > 0:
        top = float(v.max()) if v.size and v.max() > 0 else 1.0
    return (-top, top) if signed else (0.0, top)


def preview_rgb(values, mask, shade, lo, hi, name="viridis") -> np.ndarray:
    """(H, W, 3) sRGB in [0, 1]: colour-mapped ``values`` times ``shade`` on ``mask``,
    the background colour elsewhere."""
    rgb = colormap(values, lo, hi, name) * np.clip(shade, 0.0, 1.0)[..., None]
    return np.where(mask[..., None], rgb, np.asarray(BACKGROUND))


def srgb_to_linear(rgb: np.ndarray) -> np.ndarray:
    """sRGB-encoded [0, 1] -> linear light (EXR pixels are linear; viewers re-encode)."""
    rgb = np.asarray(rgb, dtype=np.float64)
    return np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)


def _format(x: float) -> str:
    return f"{x:.3g}"


def add_colorbar(picture: np.ndarray, lo: float, hi: float, name: str, label: str) -> np.ndarray:
    """A vertical colour bar with its range and ``label`` drawn in the lower right corner.

    Parameters
    ----------
    picture : (H, W, 3) uint8 sRGB

    Returns
    -------
    (H, W, 3) uint8, a new array
    """
    from PIL import Image, ImageDraw, ImageFont

    image = Image.fromarray(picture, "RGB")
    w, h = image.size
    bar_h = max(24, int(0.35 * h))
    bar_w = max(6, int(0.025 * w))
    font_size = max(9, int(0.028 * h))
    try:
        font = ImageFont.load_default(size=font_size)
    except TypeError:  # pillow without FreeType size support
        font = ImageFont.load_default()
    draw = ImageDraw.Draw(image)
    texts = [_format(hi), _format(0.5 * (lo + hi)), _format(lo)]
    text_w = max(draw.textlength(t, font=font) for t in texts + [label])
    margin = max(4, int(0.02 * w))
    x1 = w - margin - int(text_w) - 4 - bar_w
    y0 = h - margin - bar_h
    label_y = y0 - font_size // 2 - 6  # baseline of the label, clear of the top value
    # Panel behind the bar so it reads on any background.
    draw.rectangle([x1 - 4, label_y - font_size - 4, w - margin + 2, min(h - 1, h - margin + font_size // 2 + 2)],
                   fill=(255, 255, 255))
    ramp = colormap(np.linspace(hi, lo, bar_h), lo, hi, name)
    image.paste(Image.fromarray(rgb8(np.repeat(ramp[:, None, :], bar_w, axis=1)), "RGB"), (x1, y0))
    draw.rectangle([x1 - 1, y0 - 1, x1 + bar_w, y0 + bar_h], outline=(0, 0, 0))
    tx = x1 + bar_w + 4
    for frac, text in zip((0.0, 0.5, 1.0), texts):
        y = y0 + frac * (bar_h - 1)
        draw.text((tx, y), text, fill=(0, 0, 0), font=font, anchor="lm")
    draw.text((x1, label_y), label, fill=(0, 0, 0), font=font, anchor="ls")
    return np.asarray(image)


def rgb8(rgb: np.ndarray) -> np.ndarray:
    """(..., 3) float sRGB in [0, 1] -> uint8 (rounded, clamped)."""
    return (np.clip(rgb, 0.0, 1.0) * 255 + 0.5).astype(np.uint8)


QUANTITY_LABELS = {"kmax": "max |k|", "K": "Gaussian K", "H": "mean H", "k1": "k1", "k2": "k2"}


def curvature_picture(image, quantity: str = "kmax", name: str = "viridis", value_range=None, legend: bool = True):
    """Shaded curvature preview of a rendered ``image.Image``.

    Returns
    -------
    picture : (H, W, 3) uint8 sRGB, with a colour bar (when ``legend``)
    rgb : (H, W, 3) float sRGB of the surface without the colour bar
    (lo, hi) : the colour range used
    """
    values = image.channels[quantity]
    mask = image.mask
    lo, hi = value_range if value_range is not None else curvature_range(values[mask], SIGNED[quantity])
    rgb = preview_rgb(values, mask, headlight(image, ambient=0.45), lo, hi, name)
    picture = rgb8(rgb)
    if legend:
        picture = add_colorbar(picture, lo, hi, name, QUANTITY_LABELS[quantity])
    return picture, rgb, (lo, hi)


def zebra_picture(image, count: int = 16, axis=None) -> np.ndarray:
    """(H, W, 3) uint8 sRGB: reflection lines of parallel light lines (``shading.reflection_phase``)
    as black and white stripes, lightly shaded, on the background colour."""
    z = stripes(reflection_phase(image, axis), count)
    shade = 0.75 + 0.25 * headlight(image, ambient=0.0)
    grey = 0.06 + 0.9 * np.nan_to_num(z) * shade
    return rgb8(np.where(image.mask[..., None], grey[..., None] * np.ones(3), np.asarray(BACKGROUND)))
