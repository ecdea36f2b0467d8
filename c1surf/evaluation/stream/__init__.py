"""Evaluation by blocks, for outputs written without holding the whole surface (``welded``), and the vertex
blocks kept on the disk for writers that read them more than once (``spool``)."""
from .spool import SpooledTessellation
from .welded import StreamedTessellation, UndefinedNormals

__all__ = ["SpooledTessellation", "StreamedTessellation", "UndefinedNormals"]
