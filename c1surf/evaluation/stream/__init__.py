"""Evaluation by blocks, for outputs written without holding the whole surface (``welded``)."""
from .welded import StreamedTessellation, UndefinedNormals

__all__ = ["StreamedTessellation", "UndefinedNormals"]
