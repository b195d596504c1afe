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


# name → the channel's convolution, (channel (H, W), grid, kernels.Layout, grid wavelength index, boundary,
# dtype) -> degraded channel, with its `describe` (kernels.Layout, kernel radius R in pixels, grid wavelength
# indices used) -> the metadata of what was done
METHODS = Registry("convolution method", default="interp")
METHODS.register("interp", interp.convolve_channel, describe=interp.describe, summary=interp.SUMMARY,
                 reference="J. G. Nagy and D. P. O'Leary, SIAM J. Sci. Comput. 19(4), 1998")
METHODS.register("patch", patch.convolve_channel, describe=patch.describe, summary=patch.SUMMARY,
                 reference="the SOLAS paper (IS&T Electronic Imaging, 2025): one PSF per block")
DEFAULT_METHOD = METHODS.default


def check_method(method: str) -> str:
    """`method`, a name of `METHODS`; a SolasError listing them."""
    return METHODS.get(method).name


def degrade(image: np.ndarray, grid: "PSFGrid | str", method: str = DEFAULT_METHOD, boundary: str = "edge", *,
            dtype=np.float32, meta: dict | None = None, progress=None, frame=None) -> np.ndarray:
    """The linear image (H, W) or (H, W, C) seen through the lens of `grid` (a PSFGrid or its EXR path).

    method: a name of `METHODS` (each one's summary says what it does). boundary: how the image is
    padded ("edge" replicates the border, "zero", "reflect" mirrors); it is never wrapped around.
    Channels take the grid's wavelengths longest first (R, G, B ← 656, 531, 486 nm); a one-wavelength
    grid serves all.
    Returns an array of the image's shape in `dtype` (float32 or float64); `meta`, if given, is
    filled with what was done (camera, channels, blocks or nodes); `progress(done, total)` is called
    after each channel. `frame`: the frame's camera (`optics.frame.FrameCamera`; None: the image spans
    the grid's x field range)."""
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
        raise SolasError(f"a {frame.model} frame is degraded by interp (PSFs interpolated in field angle at every "
                         f"pixel), not {method}: its blocks of pixels are not blocks of field")
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
        meta.update({
            "method": method, "boundary": boundary, "camera": lay.camera.meta(),
            "channel_wavelengths_nm": [grid.wavelengths_nm[k] for k in wavelengths],
            "kernel_size_px": 2 * radius + 1, "psf_pitch_px": lay.q,
            "max_chief_ray_offset_px": float(np.abs(lay.offsets[sorted(set(wavelengths))]).max()),
            "seconds": time.perf_counter() - start,
        })
        if frame is not None:
            meta["frame_camera"] = frame.meta(width, height)
        meta.update(m.extra["describe"](lay, radius, wavelengths))
    return out if image.ndim == 3 else out[..., 0]
