"""Small batches for the batch tests: a synthetic 4×4 grid of 31 px Gaussian PSFs (no tracer) and
64×48 images, as the `batch_inputs` fixture."""
import numpy as np
import pytest

from solas_mi.psf.grid import PSFGrid, field_nodes


def gaussian_grid(size: int = 31, sigma_um: float = 8.0, pitch_um: float = 2.0) -> PSFGrid:
    """Three wavelengths × 4×4 nodes over ±2°, the same Gaussian everywhere, chief rays on the ideal image."""
    x = (np.arange(size) - size // 2) * pitch_um
    g = np.exp(-0.5 * (x[None, :] ** 2 + x[:, None] ** 2) / sigma_um ** 2)
    psfs = np.broadcast_to((g / g.sum()).astype(np.float32), (3, 4, 4, size, size)).copy()
    fx = field_nodes(4, 2.0, "centers")
    fields = np.stack(np.meshgrid(fx, fx[::-1]), axis=-1)
    chief = np.repeat(100.0 * np.tan(np.radians(fields))[None], 3, axis=0)
    meta = {"normalization": "sum", "field_range_deg": [2.0, 2.0], "field_sampling": "centers",
            "pinhole_focal_mm": 100.0, "reference_wavelength_nm": 531.0, "lens": "synthetic", "lens_hash": "0" * 16}
    return PSFGrid(psfs, fields, chief, (656.0, 531.0, 486.0), pitch_um, meta)


class BatchInputs:
    def __init__(self, root):
        self.root = root
        self.grid = root / "grid.exr"
        self.images = root / "images"
        gaussian_grid().write(str(self.grid))
        self.images.mkdir()

    def write(self, count: int, shape=(48, 64), seed: int = 0) -> list:
        from solas_mi.imageio import write_png

        rng = np.random.default_rng(seed)
        paths = []
        for i in range(count):
            paths.append(self.images / f"frame{i:03d}.png")
            write_png(paths[-1], rng.random((*shape, 3)))
        return paths


@pytest.fixture
def batch_inputs(tmp_path):
    return BatchInputs(tmp_path)
