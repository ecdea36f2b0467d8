"""Compiled loops (numba): ``kernels``, the one module that imports numba, imported only where its loops run."""
