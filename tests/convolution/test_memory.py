"""What `degrade` announces before it starts: a peak-memory estimate that covers the real peak without
crying wolf (measured in a subprocess), and a refusal, before anything is allocated, of a grid whose
PSF windows span far more of the image than any kernel could."""

import subprocess
import sys

import numpy as np
import pytest

from solas_mi import SolasError

# `solas-mi degrade` with a given number of worker threads: its estimate, then the peak resident size of
# its own memory (VmHWM; ru_maxrss would also count what the forked parent held before exec)
PEAK = """
import sys
import solas_mi.convolution.kernels as kernels
kernels.workers = lambda: int(sys.argv[4])
from solas_mi.cli import main
from solas_mi.convolution.camera import frame_fit_bytes
from solas_mi.convolution.output import peak_bytes
from solas_mi.imageio import image_size
from solas_mi.optics.calibration import MODELS
from solas_mi.psf.grid import PSFGrid
rows, cols, channels = image_size(sys.argv[1])
grid = PSFGrid.read(sys.argv[2])  # the command fits the frame's camera block too, unless it is in the cache
print(peak_bytes(sys.argv[1], rows, cols, channels, grid.data.nbytes) + frame_fit_bytes(grid, cols, rows, None,
                                                                                         MODELS.default))
assert main(["degrade", sys.argv[1], "--psf-grid", sys.argv[2], "-o", sys.argv[3]]) == 0
print(next(int(t.split()[1]) * 1024 for t in open("/proc/self/status") if t.startswith("VmHWM:")))
"""


# fitted: the frame's camera block fitted by the command; else read back from the cache of fitted cameras
@pytest.mark.parametrize(
    "suffix, threads, fitted",
    [(".png", 2, True), (".exr", 2, True), (".png", 8, True), (".exr", 8, True), (".png", 2, False)],
)
def test_the_memory_estimate_covers_the_peak(doublet, tmp_path, fresh_cache, suffix, threads, fitted):
    from solas_mi.imageio import write_exr, write_png
    from solas_mi.psf.grid import psf_grid

    grid = psf_grid(doublet, grid=(4, 4), wavelengths_nm=[656.0, 531.0, 486.0], size=64, pupil_samples=32)
    grid.write(str(tmp_path / "grid.exr"))
    rows, cols = 1500, 2000
    image = np.random.default_rng(0).random((rows, cols, 3), dtype=np.float32)
    path = tmp_path / f"image{suffix}"
    if suffix == ".png":
        write_png(path, image)
    else:
        write_exr(path, {c: image[..., i] for i, c in enumerate("RGB")})
    for _ in range(1 if fitted else 2):  # (the first run of a cached case fills the cache)
        out = subprocess.run(
            [sys.executable, "-c", PEAK, str(path), str(tmp_path / "grid.exr"), str(tmp_path / "o.exr"), str(threads)],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.split()
    estimate, peak = float(out[0]), int(out[-1])
    assert peak <= estimate <= 1.5 * peak, f"estimate {estimate / 1e6:.0f} MB, peak {peak / 1e6:.0f} MB"


def test_a_tiny_field_range_is_refused_before_allocating(doublet):
    """A grid spanning ±1e-7° makes each PSF sample 93 000 pixels of an image spanning it: the padding
    alone would take 1.8 PB (a MemoryError before). Refused with the numbers."""
    from solas_mi.convolution.methods import degrade
    from solas_mi.psf.grid import psf_grid

    grid = psf_grid(doublet, grid=(2, 2), wavelengths_nm=[531.0], field_range_deg=1e-7, size=32, pupil_samples=16)
    with pytest.raises(
        SolasError,
        match=r"32-sample windows of .* um span .* pixels of this 64x48 image.*"
        r"kernels of \d+ px exceed 2049 px",
    ):
        degrade(np.ones((48, 64)), grid)
