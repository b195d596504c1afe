"""One image file degraded by a PSF grid and written as linear OpenEXR + sRGB PNG preview, with its
metadata: what `solas-mi degrade` and every batch item do."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

from .methods import degrade

if TYPE_CHECKING:
    from ..psf.grid import PSFGrid

# input float64 + its sRGB decoding + padded planes and output (measured: 10 GB for 14000×12000×3)
BYTES_PER_VALUE = 24
GRID_META_KEYS = ("lens", "lens_hash", "method", "normalization", "field_range_deg", "field_sampling", "layout", "sensor_mm")


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
    check_memory(f"degrade {cols}x{rows}", BYTES_PER_VALUE * rows * cols * max(channels, 1), force)
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
