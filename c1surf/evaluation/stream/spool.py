"""A streamed tessellation's vertex blocks evaluated once and read back, for writers that pass over them again.

Formats whose header needs bounds (GLB's minima and maxima, OBJ's decimals)
read the vertex blocks more than once. Evaluating them again costs about as
much as the first time (the patch coefficients of scattered owners are made
again); reading them back from an unnamed temporary file beside the output
costs little and gives the same bits. The file holds (dim + 3) float64 per
vertex and disappears however the process ends.
"""
from __future__ import annotations

import tempfile

import numpy as np

__all__ = ["SpooledTessellation"]


class SpooledTessellation:
    """``tessellation``'s blocks, the vertex blocks evaluated on the first pass only.

    Parameters
    ----------
    tessellation : has ``n_vertices``, ``n_triangles``, ``dim``, ``vertex_blocks()`` yielding (points (c, dim),
        normals (c, 3)) float, ``triangle_blocks()`` (``stream.welded.StreamedTessellation``)
    folder : str, where the temporary file goes (the output's: the disk that was checked)

    A context manager: leaving it closes (and so deletes) the file. The first ``vertex_blocks()`` pass
    evaluates and keeps the blocks; every later pass reads them back, block by block, in the same sizes.
    """

    BYTES_PER_VALUE = 8

    def __init__(self, tessellation, folder: str):
        self.tessellation = tessellation
        self.n_vertices, self.n_triangles = tessellation.n_vertices, tessellation.n_triangles
        self.dim = tessellation.dim
        self.folder = folder
        self._file = None
        self._sizes: list | None = None  # rows of each kept block, once a whole pass was kept

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def vertex_blocks(self):
        """Yield (points (c, dim), normals (c, 3)) float in vertex order: evaluated once, then read back."""
        if self._sizes is None:
            yield from self._keep()
            return
        self._file.seek(0)
        width = self.dim + 3
        for rows in self._sizes:
            block = np.empty((rows, width))
            if self._file.readinto(memoryview(block).cast("B")) != block.nbytes:
                raise OSError("the temporary file of the vertex blocks is shorter than written")
            yield block[:, : self.dim], block[:, self.dim :]

    def triangle_blocks(self):
        """The tessellation's triangle blocks (integers only: made again on every pass)."""
        return self.tessellation.triangle_blocks()

    def _keep(self):
        self.close()
        self._file = tempfile.TemporaryFile(dir=self.folder)
        sizes = []
        for points, normals in self.tessellation.vertex_blocks():
            self._file.write(np.concatenate([points, normals], axis=1).tobytes())
            sizes.append(points.shape[0])
            yield points, normals
        self._sizes = sizes
