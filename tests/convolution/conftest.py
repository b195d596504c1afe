"""Synthetic PSF grids (no tracer; built by the shared `synthetic_grid`, tests/conftest.py) and direct
reference operations shared by the convolution tests, as the `synthetic` fixture."""

import math

import numpy as np
import pytest


class Synthetic:
    """Helpers for building grids and checking convolutions; `focal_mm` is the synthetic pinhole focal
    length, `make_grid` the shared grid builder's `from_psfs`."""

    def __init__(self, grids):
        self.grids = grids
        self.focal_mm, self.pixel_um, self.gaussian, self.make_grid = (
            grids.focal_mm,
            grids.pixel_um,
            grids.gaussian,
            grids.from_psfs,
        )

    @staticmethod
    def reference_convolution(image: np.ndarray, kernel: np.ndarray, shift, boundary="edge") -> np.ndarray:
        """Direct float64 convolution with one kernel (shift: whole pixels, rows, columns), padded."""
        mode = {"edge": "edge", "zero": "constant", "reflect": "symmetric"}[boundary]
        r = kernel.shape[0] // 2
        m = r + int(np.abs(shift).max())
        p = np.pad(image.astype(np.float64), m, mode=mode)
        out = np.zeros(image.shape)
        h, w = image.shape
        for a in range(2 * r + 1):
            for b in range(2 * r + 1):
                y0, x0 = m - (a - r) - shift[0], m - (b - r) - shift[1]
                out += kernel[a, b] * p[y0 : y0 + h, x0 : x0 + w]
        return out

    @staticmethod
    def centroid(image: np.ndarray) -> np.ndarray:
        """(column, row) centroid."""
        r, c = np.indices(image.shape)
        return np.array([(image * c).sum(), (image * r).sum()]) / image.sum()

    def varied_grid(
        self, rng, width, ny=8, nx=8, pitch_div=4, max_offset_px=1.0, normalization="sum", transmission=None
    ):
        """Gaussian PSFs of random widths (0.5–4 px) and random chief-ray offsets on an 8×8 grid."""
        pix = self.pixel_um(width)
        pitch = pix / pitch_div
        size = 2 * int(math.ceil(8 * pitch_div)) + 1  # ±8 px
        sig = rng.uniform(0.5, 4.0, (ny, nx)) * pix
        psfs = np.stack([[self.gaussian(size, s, pitch) for s in row] for row in sig])[None]
        if transmission is not None:
            psfs = psfs * (transmission / pitch**2)[None, :, :, None, None]
        off = rng.uniform(-max_offset_px, max_offset_px, (1, ny, nx, 2)) * pix
        return self.make_grid(psfs, pitch, off, normalization=normalization)

    @staticmethod
    def smooth_texture(rng, h, w):
        y, x = np.mgrid[0:h, 0:w]
        img = np.zeros((h, w))
        for _ in range(40):
            k = rng.normal(0, 0.25, 2)
            img += np.cos(k[0] * x + k[1] * y + rng.uniform(0, 2 * np.pi))
        return 0.5 + 0.5 * img / np.abs(img).max()

    def small_grid(self, **kw):
        return self.grids((1, 4, 4), pitch_um=1.0, size=9, sigma_um=2.0, **kw)


@pytest.fixture(scope="session")
def synthetic(synthetic_grid) -> Synthetic:
    return Synthetic(synthetic_grid)
