"""Evaluation by blocks, for outputs written without holding the whole surface (``welded``), the vertex
blocks kept on the disk for writers that read them more than once (``spool``), and what a streamed
conversion keeps of a built Surface (``kept``)."""
from .kept import StreamedSurface
from .spool import SpooledTessellation
from .welded import StreamedTessellation, UndefinedNormals

__all__ = ["SpooledTessellation", "StreamedSurface", "StreamedTessellation", "UndefinedNormals"]
