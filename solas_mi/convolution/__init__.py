"""Spatially variant convolution of images with a lens's PSF grid.

`kernels`: PSF grid → pixel kernels (exact pixel/texel integration, chief-ray offsets), padding;
`patch`: the SOLAS paper's one kernel per block; `interp`: kernels interpolated between nodes,
seamless; `methods`: the method registry and `degrade(image, grid, method)`; `spec`: the options of
degrading images as one value (`DegradeSpec`); `commands`: `degrade` on the command line.

References: the SOLAS paper's patch-wise convolution (`solas_mi` package docstring); J. G. Nagy and
D. P. O'Leary, "Restoring images degraded by spatially variant blur", SIAM J. Sci. Comput. 19(4),
1063–1082, 1998 (PSFs interpolated between grid nodes, the basis of `interp`).
"""

from ..lazy import lazy_exports

__all__ = ["DEFAULT_METHOD", "METHODS", "DegradeSpec", "degrade"]
__getattr__ = lazy_exports(
    __name__, {"DEFAULT_METHOD": ".methods", "METHODS": ".methods", "DegradeSpec": ".spec", "degrade": ".methods"}
)
