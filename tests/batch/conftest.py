"""Small batches for the batch tests: a synthetic 4×4 grid of 31 px Gaussian PSFs (no tracer, the shared
`synthetic_grid`) and 64×48 images, as the `batch_inputs` fixture."""

import numpy as np
import pytest


class BatchInputs:
    def __init__(self, root, grid):
        self.root = root
        self.grid = root / "grid.exr"
        self.images = root / "images"
        grid.write(str(self.grid))
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
def batch_inputs(tmp_path, synthetic_grid):
    """Three wavelengths × 4×4 nodes over ±2°, the same 31 px Gaussian (σ 8 µm, pitch 2 µm) everywhere."""
    return BatchInputs(tmp_path, synthetic_grid((3, 4, 4), (656.0, 531.0, 486.0), pitch_um=2.0, size=31, sigma_um=8.0))
