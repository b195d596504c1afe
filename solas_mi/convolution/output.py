"""One image file degraded by a PSF grid and written as linear OpenEXR + sRGB PNG preview, with its
metadata: what `solas-mi degrade` and every batch item do."""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import SolasError
from ..outputs import check_target
from .depth import degrade_depth
from .methods import degrade
from .spec import DegradeSpec

if TYPE_CHECKING:
    from ..psf.depth import DepthGrid
    from ..psf.grid import PSFGrid

# Peak memory of degrading one image, from the peak resident size (VmHWM) of `solas-mi degrade` on
# 1000², 2000² and 4000×3000 RGB images, both methods, an 8×8×3 grid of 160 px: the larger of two phases.
# Reading: a PNG/JPEG/TIFF (8-bit data, float64 copies for scaling and sRGB decoding) peaks at 41–42 B
# per image value (H·W·C), whatever the threads; an EXR (float32 channels, a float64 image) less than
# its convolution. Convolving: the float64 image, float32 planes, padding and output, 16–20 B per value,
# and the FFT batches in flight, which grow with the worker threads (measured 31–36 MB more per thread
# from 1 to 8; up to 44 MB more on a busy machine, where more batches wait in flight).
READ_BYTES_PER_VALUE = {"exr": 20, "other": 44}
CONVOLVE_BYTES_PER_VALUE = 22
FFT_BYTES_PER_SAMPLE = 24  # per sample of the two batches of TILE_SAMPLES in flight per worker thread
TILE_SAMPLES_PER_PIXEL = 4  # a channel's tiles hold each pixel up to 4 times (interp's hats; patch's once)
GHOST_BYTES_PER_VALUE = 24  # the ghosts' float64 frame and the flare label's layers (float64 then float32)
FIXED_BYTES = 96e6  # the interpreter, NumPy and the package's modules (measured 78 MB with a 20 MB grid read), and 16 MB
# for the allocator's slack: on a busy machine a peak came out 1 MB over the estimate with 80 MB
# the brightness convention of `degrade` beside `render-image`'s (README "PSF-grid convolution"), in every output
BRIGHTNESS = ("degrade: a sum-normalised grid (the default) keeps the input's brightness everywhere (no Fresnel loss, no "
              "relative illumination); a grid written with --normalize none carries the lens's transmission relative "
              "to its axis (vignetting), the axis staying 1. render-image: irradiance in the ideal camera's units, "
              "with Fresnel losses (--fresnel transmit, its default) and relative illumination: about 0.90 of the "
              "input on the doublet's axis (Fresnel 0.90 x pupil scale 1.0097), less toward the corners")
HALF_MAX = 65504.0
GRID_META_KEYS = ("lens", "lens_hash", "method", "normalization", "field_range_deg", "field_sampling", "layout", "sensor_mm")


def peak_bytes(image_path: str | Path, rows: int, cols: int, channels: int, grid_bytes: int, ghosts: bool = False) -> float:
    """Peak memory (bytes) of degrading the rows×cols×channels image file `image_path` with a grid of
    `grid_bytes` of PSFs: the fixed part, the grid and the larger of reading the image (by file type)
    and convolving it (its buffers and the FFT batches in flight, two per worker thread); with `ghosts`, their
    frame and the flare label too."""
    from .kernels import TILE_SAMPLES, workers

    values = rows * cols * max(channels, 1)
    read = READ_BYTES_PER_VALUE["exr" if Path(image_path).suffix.lower() == ".exr" else "other"] * values
    in_flight = min(2 * workers() * TILE_SAMPLES, TILE_SAMPLES_PER_PIXEL * rows * cols)  # a channel's tiles at most
    convolve = CONVOLVE_BYTES_PER_VALUE * values + FFT_BYTES_PER_SAMPLE * in_flight
    return FIXED_BYTES + grid_bytes + max(read, convolve) + (GHOST_BYTES_PER_VALUE * values if ghosts else 0)


def read_depth(path: str | Path) -> np.ndarray:
    """A depth map (m) from an EXR file: as the depth labels are read (`labelkinds.KINDS`: its depth.Z, Z,
    depth or Y channel, or its only one)."""
    from ..labelkinds import KINDS

    return KINDS["depth"].function(path)[..., 0]


# many parameters: the item's files (image, grid, outputs, depth map, labels) beside the spec and the run's settings
def degrade_file(image_path: str | Path, grid: PSFGrid | DepthGrid, grid_path: str | Path, output: Path, png: Path,
                 spec: DegradeSpec | None = None, *, force: bool = False, depth: str | Path | None = None,
                 extra_meta: dict[str, Any] | None = None, progress: Callable[[int, int], None] | None = None,
                 labels=None, calibration_model: str | None = None, lens=None, written: dict | None = None) -> dict:
    """Degrade the image file `image_path` by `grid` (read from `grid_path`, named in the metadata) as
    `spec` says (a `convolution.spec.DegradeSpec`: method, boundary, linear, output format, occlusion,
    silhouette, frame camera; None: its defaults) and write `output` and `png` (`spec.OUTPUT_FILES`' two files)
    together or not at all; returns the output's metadata. `force`: run even when the estimated memory
    exceeds what is free; `depth`: the EXR depth map (m) of the image, with a grid over object distance
    (`convolution.depth`); `extra_meta` is added to the metadata (its "camera", the fitted camera block of
    `convolution.camera`, to the convolution's own "camera"); `progress(done, total)` after each
    channel; `labels`: the frame's label files (kind → file, `labelkinds.KINDS`), warped by the image's
    mapping and written beside `output` (`labels.label_outputs`) with the rest, all read and checked first;
    `calibration_model`: the frame's camera block fitted here (`convolution.camera.frame_camera`, its memory
    in the estimate unless the cache of fitted cameras holds it; a batch fits it once and gives it in `extra_meta` instead);
    `lens`: with `spec.ghosts`, the grid's lens (None: read again from the grid's metadata, `camera.grid_lens`): its
    ghosts of the frame's sources added (`convolution.ghosts`), the flare label beside the output; `written`: a dict
    that gets the degraded image ("image") for a caller that goes on with it (a batch's camera), not read back."""
    from ..budget import check_memory
    from ..imageio import image_size, read_image
    from ..psf.depth import DepthGrid
    from .camera import frame_camera, frame_fit_bytes
    from .ghosts import FrameGhosts
    from .labels import label_outputs, memory_bytes, read_labels

    spec = DegradeSpec() if spec is None else spec
    if not isinstance(spec, DegradeSpec):
        raise SolasError(f"spec {spec!r} must be a solas_mi.convolution.spec.DegradeSpec")
    if (depth is not None) != isinstance(grid, DepthGrid):
        raise SolasError(f"PSF grid {grid_path}: " + ("a depth map needs a grid over object distance (psf-grid "
                         "--distances-m)" if depth is not None else "a grid over object distance needs the image's "
                         "depth map (--depth)"))
    rows, cols, channels = image_size(image_path)
    if not rows:  # its header unreadable (a missing or broken file): the reader says why, before any estimate
        rows, cols, channels = np.atleast_3d(read_image(image_path, linearize=False)).shape
    layers = grid.layers if depth is not None else [grid]
    files = dict(labels or {})
    targets = label_outputs(output, files, flare=spec.ghosts)
    for target in targets.values():
        check_target(target, [image_path, grid_path, depth, output, png, *files.values()], "labels output")
    need = peak_bytes(image_path, rows, cols, channels, sum(g.data.nbytes for g in layers), spec.ghosts)
    need += 9 * len(layers) * rows * cols
    fitting = frame_fit_bytes(grid, cols, rows, spec.frame, calibration_model)
    check_memory(f"degrade {cols}x{rows}", need + memory_bytes(rows * cols, files) + fitting, force)
    found = read_labels(files, (rows, cols), image_path)  # every label read and checked before any work
    ghosts = FrameGhosts.plan(image_path, grid, spec, force, lens, depth)  # None without spec.ghosts
    extra = {} if calibration_model is None else {"camera": frame_camera(grid, cols, rows, spec.frame, calibration_model)}
    extra.update(extra_meta or {})
    image = read_image(image_path, linearize=not spec.linear)
    meta: dict[str, Any] = {}
    out, depth_m = convolve(image, grid, spec, depth, meta, progress)
    flare = {} if ghosts is None else ghosts.add(image, out, meta)
    writers = warped_labels(found, targets, grid, out.shape[:2], spec, depth_m, meta, flare)
    describe_item(meta, image_path, spec, grid_path, layers[0], extra)
    names = None if out.ndim == 2 or out.shape[-1] == 3 else \
        [f"C{c:02d}_{meta['channel_wavelengths_nm'][c]:g}nm" for c in range(out.shape[-1])]
    write_output(output, png, out, names, meta, spec.output_format, image_path, writers)
    meta["output_shape"] = list(out.shape)
    (written if written is not None else {})["image"] = out
    return meta


def convolve(image: np.ndarray, grid, spec: DegradeSpec, depth, meta: dict, progress) -> tuple[np.ndarray, Any]:
    """The image degraded by `grid` as `spec` says (with the depth map file `depth`: by depth layers), what was
    done in `meta`; and the depth map as read (None without)."""
    if depth is None:
        return degrade(image, grid, spec.method, spec.boundary, meta=meta, progress=progress, frame=spec.frame), None
    if spec.method != "interp":
        raise SolasError(f"method {spec.method!r}: a depth map is convolved with interp per depth layer only")
    depth_m = read_depth(depth)
    out = degrade_depth(image, depth_m, grid, spec.boundary, occlusion=spec.occlusion, meta=meta,
                        progress=progress, frame=spec.frame, silhouette=spec.silhouette)
    meta["depth_map"] = str(depth)
    return out, depth_m


def describe_item(meta: dict, image_path, spec: DegradeSpec, grid_path, first, extra: dict) -> None:
    """The degraded image's metadata `meta` completed: its input, the grid (`first`: its one grid, or its first
    layer) and the brightness convention, then `extra` (its "camera", the fitted camera block of
    `convolution.camera`, joining the convolution's own "camera")."""
    meta.update({"input": str(image_path), "input_encoding": "linear" if spec.linear or
                 Path(image_path).suffix.lower() == ".exr" else "sRGB, decoded to linear",
                 "psf_grid": str(grid_path),
                 "psf_grid_meta": {key: first.meta.get(key) for key in GRID_META_KEYS},
                 "psf_grid_shape": list(first.shape), "psf_pitch_um": first.pitch_um, "psf_size": first.size,
                 "values": "mean irradiance over each pixel, in the units of the linear input",
                 "brightness": BRIGHTNESS})
    extra = dict(extra)
    if "camera" in extra:
        meta["camera"] = {**meta.get("camera", {}), **extra.pop("camera")}
    meta.update(extra)


def warped_labels(found: dict, targets: dict, grid, shape: tuple[int, int], spec: DegradeSpec,
                  depth_m: np.ndarray | None, meta: dict, flare: dict | None = None) -> dict:
    """The labels `found` (`labels.read_labels`) warped by the mapping the image went through (its depth map
    `depth_m` as the convolution read it) and the flare label's layers `flare` (`ghosts.FrameGhosts.add`), recorded
    in `meta["labels"]`: each of the files `targets` (`labels.label_outputs`) → its writer (`write_output`); {}
    without either."""
    if not found and not flare:
        return {}
    from ..labelkinds import MAX_RATIO
    from .depth import silhouette_depth
    from .ghosts import FLARE_ABOUT
    from .labels import label_writers, warp_labels
    from .mapping import mapping_for

    layers: dict = {}
    annotations, about = None, {}  # type: dict | None, dict
    if found:
        depth = None if depth_m is None else silhouette_depth(np.asarray(depth_m, dtype=np.float64), spec.silhouette)[0]
        mapping = mapping_for(grid, shape[1], shape[0], spec.frame, spec.method, depth)
        layers, annotations, about = warp_labels(found, mapping, spec.boundary)
    layers.update(flare or {})
    meta["labels"] = {**about, **({"flare": FLARE_ABOUT.format(cap=MAX_RATIO)} if flare else {}),
                      "outputs": {what: str(path) for what, path in targets.items()}}
    return label_writers(targets, layers, annotations, meta["labels"])


def write_output(output: Path, second: Path, out: np.ndarray, names: list[str] | None, meta: dict,
                 output_format: str, image_path, more: dict | None = None) -> None:
    """The degraded image `out` (channel `names`, None: grey or RGB) and its metadata as `output_format`
    says (`spec.OUTPUT_FILES`): the EXR and its PNG preview, or the 16-bit PNG and its JSON; and `more`
    files (path → its writer of a temporary path: the warped labels); all appear together or not at all."""
    from ..imageio import image_channels, write_exr, write_png
    from ..outputs import written_together

    view = out if out.ndim == 2 or out.shape[-1] == 3 else out.mean(axis=-1)
    half = output_format == "exr-half"
    if half and float(np.abs(out).max()) > HALF_MAX:
        raise SolasError(f"{image_path}: degraded values up to {float(np.abs(out).max()):.4g} exceed half floats' "
                         f"{HALF_MAX:g}: write float EXR (output format exr)")
    meta["output_format"] = output_format
    more = more or {}
    with written_together(output, second, *more) as (tmp_data, tmp_second, *tmp_more):
        if output_format == "png16":
            write_png16_with_meta(tmp_data, tmp_second, out if names is None else view, meta)
        else:
            write_exr(tmp_data, image_channels(out, names), meta, half=half)
            write_png(tmp_second, view)
        for tmp, writer in zip(tmp_more, more.values()):
            writer(tmp)


def write_png16_with_meta(path: str, meta_path: str, image: np.ndarray, meta: dict) -> None:
    """`image` as a 16-bit sRGB PNG (more than 3 channels: their mean, as the preview) and `meta` as JSON,
    saying how many values were clipped to [0, 1] and how to read the file back to linear values."""
    from .. import jsonio
    from ..imageio import write_png16, write_text

    meta["png16"] = {"clipped_values": write_png16(path, image), "encoding": "sRGB, 16 bits; values clipped to "
                     "[0, 1]; read back linear with solas_mi.imageio.read_image (within 2e-5)"}
    write_text(meta_path, jsonio.dumps(meta, indent=1, default=str) + "\n")
