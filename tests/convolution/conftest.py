"""Synthetic PSF grids (no tracer) and direct reference operations shared by the convolution tests,
as the `synthetic` fixture."""
import math

import numpy as np
import pytest

from solas_mi.psf.grid import PSFGrid, field_nodes


class Synthetic:
    """Helpers for building grids and checking convolutions; `focal_mm` is the synthetic pinhole focal length."""

    focal_mm = 100.0

    @staticmethod
    def pixel_um(width: int, fov: float = 2.0) -> float:
        return 2e3 * Synthetic.focal_mm * math.tan(math.radians(fov)) / width

    @staticmethod
    def gaussian(size: int, sigma_um: float, pitch_um: float) -> np.ndarray:
        x = (np.arange(size) - size // 2) * pitch_um
        g = np.exp(-0.5 * (x[None, :] ** 2 + x[:, None] ** 2) / sigma_um ** 2)
        return g / g.sum()

    @staticmethod
    def make_grid(psfs, pitch_um, offsets_um=None, field=(2.0, 2.0), wavelengths=None, normalization="sum",
                  sampling="centers") -> PSFGrid:
        """A PSFGrid without the tracer: psfs (n_wavelengths, ny, nx, s, s); chief rays = the ideal image
        points + offsets_um (n_wavelengths, ny, nx, 2) µm (x right, y up)."""
        psfs = np.asarray(psfs, dtype=np.float32)
        nw, ny, nx = psfs.shape[:3]
        fx = field_nodes(nx, field[0], sampling)
        fy = field_nodes(ny, field[1], sampling)[::-1]
        fields = np.stack(np.meshgrid(fx, fy), axis=-1)
        chief = np.repeat(Synthetic.focal_mm * np.tan(np.radians(fields))[None], nw, axis=0)
        if offsets_um is not None:
            chief = chief + np.asarray(offsets_um, dtype=np.float64) * 1e-3
        meta = {"normalization": normalization, "field_range_deg": list(field), "field_sampling": sampling,
                "pinhole_focal_mm": Synthetic.focal_mm, "reference_wavelength_nm": 531.0}
        wl = tuple(wavelengths) if wavelengths else tuple(531.0 + 50.0 * k for k in range(nw))
        return PSFGrid(psfs, fields, chief, wl, float(pitch_um), meta)

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
                out += kernel[a, b] * p[y0:y0 + h, x0:x0 + w]
        return out

    @staticmethod
    def centroid(image: np.ndarray) -> np.ndarray:
        """(column, row) centroid."""
        r, c = np.indices(image.shape)
        return np.array([(image * c).sum(), (image * r).sum()]) / image.sum()

    @staticmethod
    def varied_grid(rng, width, ny=8, nx=8, pitch_div=4, max_offset_px=1.0, normalization="sum", transmission=None):
        """Gaussian PSFs of random widths (0.5–4 px) and random chief-ray offsets on an 8×8 grid."""
        pix = Synthetic.pixel_um(width)
        pitch = pix / pitch_div
        size = 2 * int(math.ceil(8 * pitch_div)) + 1  # ±8 px
        sig = rng.uniform(0.5, 4.0, (ny, nx)) * pix
        psfs = np.stack([[Synthetic.gaussian(size, s, pitch) for s in row] for row in sig])[None]
        if transmission is not None:
            psfs = psfs * (transmission / pitch ** 2)[None, :, :, None, None]
        off = rng.uniform(-max_offset_px, max_offset_px, (1, ny, nx, 2)) * pix
        return Synthetic.make_grid(psfs, pitch, off, normalization=normalization)

    @staticmethod
    def smooth_texture(rng, h, w):
        y, x = np.mgrid[0:h, 0:w]
        img = np.zeros((h, w))
        for _ in range(40):
            k = rng.normal(0, 0.25, 2)
            img += np.cos(k[0] * x + k[1] * y + rng.uniform(0, 2 * np.pi))
        return 0.5 + 0.5 * img / np.abs(img).max()

    @staticmethod
    def small_grid(**kw):
        return Synthetic.make_grid(np.broadcast_to(Synthetic.gaussian(9, 2.0, 1.0), (1, 4, 4, 9, 9)), 1.0, **kw)


@pytest.fixture(scope="session")
def synthetic() -> Synthetic:
    return Synthetic
