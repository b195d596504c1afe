"""Spatially variant convolution of images with a lens's PSF grid (`solas-mi degrade`).

`kernels`: PSF grid → pixel kernels (exact pixel/texel integration, chief-ray offsets), padding;
`patch`: the SOLAS paper's one kernel per block; `interp`: kernels interpolated between nodes,
seamless; `commands`: `degrade` and the command line.
"""
from .commands import DEFAULT_METHOD, METHODS, degrade, register
from .kernels import BOUNDARIES

__all__ = ["BOUNDARIES", "DEFAULT_METHOD", "METHODS", "degrade", "register"]
