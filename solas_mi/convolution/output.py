"""One image file degraded by a PSF grid and written as linear OpenEXR + sRGB PNG preview, with its
metadata: what `solas-mi degrade` and every batch item do."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

from .methods import degrade

if TYPE_CHECKING:
    from ..psf.grid import PSFGrid

# Peak memory of one degraded image above the fixed part, per image value (H·W·C), from the peak
# resident size (ru_maxrss) of `solas-mi degrade` on 1000², 2000² and 4000×3000 RGB images, both methods,
# 8×8×3 grid of 160 px, 2 cores: an EXR input (read as float64, planes in float32) 34, 25 and 20 B; a
# PNG/JPEG/TIFF (8-bit data, float64 copies for scaling and sRGB decoding) 42, 41 and 42 B. The
# estimate covers the peaks (1.1–1.3× at 2000² and beyond; more at 1000², where the fixed part rules).
BYTES_PER_VALUE = {"exr": 22, "other": 42}
FIXED_BYTES = 80e6  # the interpreter, NumPy and the package's modules (measured 78 MB with a 20 MB grid read)
# the FFT batches in flight, per sample: float32 tiles and kernels, their complex64 spectra, the results
# (and the threads' malloc arenas: the peak varies by about 40 MB from run to run)
FFT_BYTES_PER_SAMPLE = 32
GRID_META_KEYS = ("lens", "lens_hash", "method", "normalization", "field_range_deg", "field_sampling", "layout", "sensor_mm")


def peak_bytes(image_path: str | Path, rows: int, cols: int, channels: int, grid_bytes: int) -> float:
    """Peak memory (bytes) of degrading the rows×cols×channels image file `image_path` with a grid of
    `grid_bytes` of PSFs: the fixed part, the grid, the FFT batches in flight (two per worker thread)
    and the image's own buffers (`BYTES_PER_VALUE`, by file type)."""
    from .kernels import TILE_SAMPLES, workers

    kind = "exr" if Path(image_path).suffix.lower() == ".exr" else "other"
    return (FIXED_BYTES + grid_bytes + 2 * workers() * TILE_SAMPLES * FFT_BYTES_PER_SAMPLE
            + BYTES_PER_VALUE[kind] * rows * cols * max(channels, 1))


def degrade_file(image_path: str | Path, grid: "PSFGrid", grid_path: str | Path, output: Path, png: Path,
                 method: str, boundary: str, *, linear: bool = False, force: bool = False,
                 extra_meta: dict[str, Any] | None = None,
                 progress: Callable[[int, int], None] | None = None) -> dict[str, Any]:
    """Degrade the image file `image_path` by `grid` (read from `grid_path`, named in the metadata) and
    write `output` (EXR) and `png` together or not at all; returns the output's metadata.
    `linear`: PNG/JPEG values are already linear (not sRGB-decoded); `force`: run even when the
    estimated memory exceeds what is free; `extra_meta` is added to the metadata."""
    from ..budget import check_memory
    from ..imageio import image_channels, image_size, read_image, write_exr, write_png
    from ..outputs import written_together

    rows, cols, channels = image_size(image_path)
    check_memory(f"degrade {cols}x{rows}", peak_bytes(image_path, rows, cols, channels, grid.data.nbytes), force)
    image = read_image(image_path, linearize=not linear)
    meta: dict[str, Any] = {}
    out = degrade(image, grid, method, boundary, meta=meta, progress=progress)
    meta.update({"input": str(image_path), "input_encoding": "linear" if linear or
                 Path(image_path).suffix.lower() == ".exr" else "sRGB, decoded to linear",
                 "psf_grid": str(grid_path),
                 "psf_grid_meta": {key: grid.meta.get(key) for key in GRID_META_KEYS},
                 "psf_grid_shape": list(grid.shape), "psf_pitch_um": grid.pitch_um, "psf_size": grid.size,
                 "values": "mean irradiance over each pixel, in the units of the linear input"})
    meta.update(extra_meta or {})
    names = None if out.ndim == 2 or out.shape[-1] == 3 else \
        [f"C{c:02d}_{meta['channel_wavelengths_nm'][c]:g}nm" for c in range(out.shape[-1])]
    view = out if out.ndim == 2 or out.shape[-1] == 3 else out.mean(axis=-1)
    # both files appear together or not at all
    with written_together(output, png) as (tmp_exr, tmp_png):
        write_exr(tmp_exr, image_channels(out, names), meta)
        write_png(tmp_png, view)
    meta["output_shape"] = list(out.shape)
    return meta
