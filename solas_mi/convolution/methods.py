"""The convolution methods by name (`METHODS`, a `solas_mi.registry.Registry`: the one list every caller
uses) and `degrade`, their one dispatcher: an image seen through a lens, by spatially variant
convolution with its PSF grid.

The input image is the ideal (pinhole) image of the scene spanning the grid's ±x field range; its
pixel grid is the sensor (`kernels.grid_camera`).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..blas import single_threaded_blas
from ..errors import SolasError
from ..imageio import check_finite
from ..registry import Registry
from . import interp, patch
from .curved import CurvedLayout, frame_layout
from .kernels import channel_wavelengths, check_boundary, check_kernel

if TYPE_CHECKING:
    from ..psf.grid import PSFGrid


DEFAULT_METHOD = "interp"
"""The convolution method taken when none is given."""
METHODS = Registry("convolution method", default=DEFAULT_METHOD)
"""The convolution methods by name (a `solas_mi.registry.Registry`; the [table of methods](registries.md)). Each
entry's function convolves one channel, ``(channel (H, W), grid, kernels.Layout, grid wavelength index, boundary,
dtype) -> degraded channel``, and its ``describe`` ``(kernels.Layout, kernel radius R in pixels, grid wavelength
indices used)`` gives the metadata of what was done."""
METHODS.register(
    "interp",
    interp.convolve_channel,
    describe=interp.describe,
    summary=interp.SUMMARY,
    reference="J. G. Nagy and D. P. O'Leary, SIAM J. Sci. Comput. 19(4), 1998",
)
METHODS.register(
    "patch",
    patch.convolve_channel,
    describe=patch.describe,
    summary=patch.SUMMARY,
    reference="the SOLAS paper (IS&T Electronic Imaging, 2025): one PSF per block",
)


def check_method(method: str) -> str:
    """`method`, a name of `METHODS`; a SolasError listing them."""
    return METHODS.get(method).name


# long: the public API's numpydoc docstring is half of it
def degrade(
    image: np.ndarray,
    grid: PSFGrid | str,
    method: str = DEFAULT_METHOD,
    boundary: str = "edge",
    *,
    dtype=np.float32,
    meta: dict | None = None,
    progress=None,
    frame=None,
) -> np.ndarray:
    """A linear image as the lens of a PSF grid sees it: spatially variant convolution.

    The image is the ideal image of the grid's field (`optics.camera`); channels take the grid's
    wavelengths longest first (R, G, B ← 656, 531, 486 nm), a one-wavelength grid serving all
    ([the convolution in depth](../details/convolution.md)).

    Parameters
    ----------
    image : numpy.ndarray
        (H, W) or (H, W, C) linear values.
    grid : PSFGrid or str
        The PSF grid, or the path of its EXR file.
    method : str, default "interp"
        A name of `METHODS` (each one's summary says what it does).
    boundary : str, default "edge"
        How the image is padded, never wrapped around: "edge" replicates the border, "zero" pads with
        black, "reflect" mirrors.
    dtype : numpy dtype, default float32
        float32 or float64.
    meta : dict, optional
        Filled with what was done: camera, channels' wavelengths, kernel size, blocks or nodes.
    progress : callable, optional
        Called as ``progress(done, total)`` after each channel.
    frame : FrameCamera, optional
        The camera the frame was taken with (`optics.frame.FrameCamera`); default: the image spans the
        grid's x field range.

    Returns
    -------
    numpy.ndarray
        The degraded image, of the image's shape, in `dtype`.

    Raises
    ------
    SolasError
        For a bad method, boundary, dtype, grid or image (empty, not numbers, NaN or infinite values),
        a frame a method cannot take, or kernels too large for the image.

    Examples
    --------
    >>> import numpy as np
    >>> from solas_mi import Lens
    >>> from solas_mi.convolution import degrade
    >>> from solas_mi.psf import psf_grid
    >>> grid = psf_grid(Lens.load("solas-doublet"), grid=(2, 2), size=32)
    >>> point = np.zeros((48, 64, 3), np.float32)
    >>> point[24, 32] = 1.0
    >>> blurred = degrade(point, grid)
    >>> blurred.shape, round(float(blurred.sum()), 4)
    ((48, 64, 3), 3.0)
    """
    from ..psf.grid import PSFGrid

    check_method(method)
    check_boundary(boundary)
    dtype = np.dtype(dtype)
    if dtype not in (np.float32, np.float64):
        raise SolasError(f"dtype {dtype} must be float32 or float64")
    if isinstance(grid, (str, Path)):
        grid = PSFGrid.read(str(grid))
    if not isinstance(grid, PSFGrid):
        raise SolasError(f"grid {type(grid).__name__} must be a PSFGrid or the path of its EXR file")
    image = np.asarray(image)
    if image.ndim not in (2, 3) or image.size == 0 or not np.issubdtype(image.dtype, np.number):
        raise SolasError(f"image of shape {image.shape} must be a non-empty H×W or H×W×C array of numbers")
    planes = check_finite(image[..., None] if image.ndim == 2 else image, "image")  # a NaN would spread
    height, width, nchan = planes.shape
    wavelengths = channel_wavelengths(grid, nchan)
    lay = frame_layout(grid, width, height, frame)
    if isinstance(lay, CurvedLayout) and method != "interp":
        raise SolasError(
            f"a {frame.model} frame is degraded by interp (PSFs interpolated in field angle at every "
            f"pixel), not {method}: its blocks of pixels are not blocks of field"
        )
    radius = check_kernel(grid, lay)  # before any allocation
    m = METHODS[method]
    start = time.perf_counter()
    out = np.empty(planes.shape, dtype=dtype)
    with single_threaded_blas():
        for c, k in enumerate(wavelengths):
            out[..., c] = m.function(planes[..., c], grid, lay, k, boundary, dtype)
            if progress is not None:
                progress(c + 1, nchan)
    if meta is not None:
        meta.update(
            {
                "method": method,
                "boundary": boundary,
                "camera": lay.camera.meta(),
                "channel_wavelengths_nm": [grid.wavelengths_nm[k] for k in wavelengths],
                "kernel_size_px": 2 * radius + 1,
                "psf_pitch_px": lay.q,
                "max_chief_ray_offset_px": float(np.abs(lay.offsets[sorted(set(wavelengths))]).max()),
                "seconds": time.perf_counter() - start,
            }
        )
        if frame is not None:
            meta["frame_camera"] = frame.meta(width, height)
        meta.update(m.extra["describe"](lay, radius, wavelengths))
    return out if image.ndim == 3 else out[..., 0]
