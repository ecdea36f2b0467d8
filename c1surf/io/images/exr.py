"""OpenEXR images of named float32 channels (OpenEXR 3.x ``OpenEXR.File`` API).

Two traps of the binding are handled here: it writes silently wrong pixels from
non-contiguous arrays (so every channel is copied to a C-contiguous float32
array), and it adds entries to the header dict it is given (so it gets a fresh
dict every time).
"""
from __future__ import annotations

import numpy as np

from ..errors import MeshInputError, OutputError
from ..finite import refuse_non_finite

__all__ = ["write_exr", "read_exr"]


def write_exr(path, channels: dict, attributes: dict | None = None) -> None:
    """Write a scanline EXR with one FLOAT channel per entry of ``channels``.

    Parameters
    ----------
    path : str or PathLike
    channels : dict name -> (H, W) array, all of one shape
    attributes : dict or None, extra header attributes (str, float, int, or float32
        arrays of 2, 3 or 4x4 values, as the binding maps them)
    """
    import OpenEXR

    shapes = {np.shape(a) for a in channels.values()}
    if len(shapes) != 1 or len(next(iter(shapes))) != 2:
        raise ValueError(f"every channel must be one (H, W) array, got shapes {sorted(shapes)}")
    data = {str(name): np.ascontiguousarray(a, dtype=np.float32) for name, a in channels.items()}
    for name, values in data.items():  # +inf is the depth of the background (Z), nothing else
        refuse_non_finite(values, f"'{name}' channel values", path, allow_positive_infinity=name == "Z")
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for key, value in (attributes or {}).items():
        header[str(key)] = np.array(value, dtype=np.float32) if isinstance(value, (list, tuple, np.ndarray)) else value
    try:
        with OpenEXR.File(dict(header), data) as f:
            f.write(str(path))
    except Exception as e:  # the binding raises plain RuntimeError / ValueError
        raise OutputError(str(path), f"cannot write the EXR image ({e})") from None


def read_exr(path) -> tuple[dict, dict]:
    """Read every channel of an EXR file.

    Returns
    -------
    channels : dict name -> (H, W) array (float32 for FLOAT channels)
    header : dict, the file's header attributes
    """
    import OpenEXR

    try:
        with OpenEXR.File(str(path), separate_channels=True) as f:
            header = dict(f.header())
            channels = {name: np.array(c.pixels) for name, c in f.channels().items()}
    except Exception as e:
        raise MeshInputError(str(path), f"cannot read the EXR image ({e})") from None
    return channels, header
