"""PNG pictures through pillow: (H, W, 3) uint8 sRGB arrays (``render.pictures``) to files."""
from __future__ import annotations

import numpy as np

__all__ = ["write_png"]


def write_png(path, picture: np.ndarray) -> None:
    """Write an optimized RGB PNG.

    Parameters
    ----------
    path : str or PathLike
    picture : (H, W, 3) uint8 sRGB
    """
    from PIL import Image

    picture = np.asarray(picture)
    if picture.dtype != np.uint8 or picture.ndim != 3 or picture.shape[2] != 3:
        raise ValueError(f"a PNG picture is an (H, W, 3) uint8 array, got {picture.dtype} {picture.shape}")
    Image.fromarray(picture, "RGB").save(str(path), format="PNG", optimize=True)
