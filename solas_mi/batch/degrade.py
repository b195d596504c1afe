"""A batch of images degraded by one PSF grid: `degrade_batch` (the work) and `plan_batch` (what a
run would do, for --dry-run).

The grid is a given file, or computed from a lens once per batch through the `GridCache` and shared
with every worker. Items a former run of the same batch finished (outputs unchanged) are skipped;
every other item is done, and its result (done or failed, with the error) recorded in the manifest.
"""
from __future__ import annotations

import hashlib
import json
import os
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Iterable

from ..errors import SolasError
from .cache import GridCache, file_hash
from .jobs import MANIFEST, Job, Manifest, add_outputs, expand_inputs, plan, say_skipped
from .runner import check_dask

# seconds per image value (H·W·C) on one core of the 2-core benchmark machine, reading, degrading
# (interp) and writing included (benchmarks/bench_batch.py: 1280×960 RGB, 32×32 grid)
SECONDS_PER_VALUE = 2.0e-7
# a worker process's own memory before its first item (VmRSS of a spawned process with the modules an
# item imports, measured: degrade — numpy, OpenEXR, the convolution — 37 MB; render — Mitsuba with its
# spectral variant set — 110 MB), added to each worker's items' peak in the estimates
WORKER_BYTES = {"degrade": 37e6, "render": 110e6}


@dataclass
class BatchPlan:
    """What a batch will do: its items (skipped ones marked), the grid and where it comes from."""

    jobs: list[Job]
    manifest: Manifest
    key: str  # the batch's identity: the grid, method, boundary and input encoding
    grid_path: Path
    grid_source: str  # "given", "cache hit" or "to compute"
    lens: Any = None
    spec: Any = None  # the grid's `psf.spec.GridSpec` when computed from the lens

    @property
    def todo(self) -> list[int]:
        return [i for i, job in enumerate(self.jobs) if job.status != "skipped"]


@dataclass
class BatchResult:
    """A finished batch: its items, manifest path and where its grid came from (a render batch: none)."""

    jobs: list[Job]
    manifest: Path
    grid_path: Path | None
    grid_source: str
    seconds: float

    @property
    def failed(self) -> list[Job]:
        return [job for job in self.jobs if job.status == "failed"]

    def count(self, status: str) -> int:
        return sum(job.status == status for job in self.jobs)


def check_workers(workers: int | None, dask: str | None = None) -> int:
    """The number of worker processes: `workers` (default: the cores), SolasError unless a whole number
    >= 1; processes of this machine (local ones, a Dask LocalCluster) capped at its cores, said so on
    stderr (more processes than cores only add their memory, WORKER_BYTES each, and no speed)."""
    cores = os.cpu_count() or 1
    n = cores if workers is None else workers
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise SolasError(f"workers {workers!r} must be a whole number >= 1")
    if n > cores and dask in (None, "local"):
        print(f"--workers {n}: using {cores}, the cores of this machine (each worker costs about "
              f"{WORKER_BYTES['degrade'] / 1e6:.0f}-{WORKER_BYTES['render'] / 1e6:.0f} MB before its first item)",
              file=sys.stderr, flush=True)
        n = cores
    return n


def plan_batch(inputs: Iterable[str | os.PathLike], output_dir: str | os.PathLike, *,
               psf_grid: str | os.PathLike | None = None, lens=None, grid_spec=None,
               method: str = "interp", boundary: str = "edge", linear: bool = False,
               cache: GridCache | str | os.PathLike | None = None, output_format: str = "exr",
               depth_pattern: str | None = None, frame=None, depth_options: tuple[str, ...] = ("filled", "nearest"),
               camera=None) -> BatchPlan:
    """Check everything a batch needs before any work and find what a former run finished; `depth_options`:
    the occlusion and silhouette rules, part of a depth batch's identity."""
    from ..convolution.kernels import check_boundary
    from ..convolution.methods import check_method
    from ..outputs import output_folder

    check_method(method)
    check_boundary(boundary)
    if (psf_grid is None) == (lens is None):
        raise SolasError("give either a PSF grid file or a lens to compute one from, not both and not neither")
    out_dir = output_folder(output_dir).resolve()
    roots: dict[Path, Path] = {}  # folders are read as trees, their structure kept in the output folder
    labels: list[tuple[Path, str]] = []
    files = expand_inputs(inputs, roots=roots, skipped=labels)
    depths = {f: depth_file(f, depth_pattern) for f in files} if depth_pattern is not None else {}
    images = [f for f in files if f not in set(depths.values())]  # depth maps are no inputs
    say_skipped([(f, why) for f, why in labels if f not in set(depths.values())])  # those not the frames' depth maps
    missing = [str(depths[f]) for f in images if depths and not depths[f].is_file()]
    if missing:
        raise SolasError(f"{len(missing)} image(s) have no depth map by the pattern {depth_pattern!r}, e.g. {missing[0]}")
    from ..convolution.output import OUTPUT_FILES

    if output_format not in OUTPUT_FILES:
        raise SolasError(f"output format {output_format!r} must be one of {', '.join(OUTPUT_FILES)}")
    jobs = plan(images, out_dir, roots, OUTPUT_FILES[output_format])
    with_camera(jobs, camera, files, output_format)
    for job in jobs:
        if depths:
            job.params["depth"] = str(depths[Path(job.input)])
    spec = None
    if psf_grid is not None:
        grid_path = Path(psf_grid).resolve()
        if not grid_path.is_file():
            raise SolasError(f"PSF grid {str(psf_grid)!r} is not a file; give an EXR written by `solas-mi psf-grid`")
        grid_id, source = file_hash(grid_path), "given"
    else:
        from ..optics.lens import Lens
        from ..psf.spec import GridSpec

        lens = lens if isinstance(lens, Lens) else Lens.load(str(lens))
        cache = cache if isinstance(cache, GridCache) else GridCache(cache)
        spec = GridSpec() if grid_spec is None else grid_spec
        if not isinstance(spec, GridSpec):
            raise SolasError(f"grid_spec {grid_spec!r} must be a solas_mi.psf.spec.GridSpec")
        grid_path = cache.path(lens, spec)
        hit = grid_path.is_file() and cache.check(grid_path, lens, spec) is None
        grid_id, source = grid_path.stem, "cache hit" if hit else "to compute"
    identity = [grid_id, method, boundary, linear] + ([output_format] if output_format != "exr" else []) + (
        [depth_pattern, *depth_options] if depth_pattern is not None else []) + (
        [asdict(frame)] if frame is not None else []) + ([camera.describe()] if camera is not None else [])
    key = hashlib.sha256(json.dumps(identity).encode()).hexdigest()[:16]
    manifest = Manifest(out_dir / MANIFEST, {"version": 1, "kind": "degrade", "batch_id": key}, jobs)
    manifest.resume(key)
    return BatchPlan(jobs, manifest, key, grid_path, source, lens, spec)


def with_camera(jobs: list[Job], camera, sources, output_format: str = "exr") -> None:
    """The camera's outputs (`isp.camera.Camera`: RAW, developed frame) added to each item; None: none."""
    if camera is None:
        return
    from ..isp.camera import Camera, camera_outputs

    if not isinstance(camera, Camera):
        raise SolasError(f"camera {camera!r} must be a solas_mi.isp.camera.Camera")
    if output_format == "png16":
        raise SolasError("a camera reads each item's irradiance from its EXR: write exr or exr-half, not png16 "
                         "(16-bit sRGB, clipped to [0, 1])")
    add_outputs(jobs, lambda output: camera_outputs(output, camera), sources)


def depth_file(image: Path, pattern: str) -> Path:
    """The depth map of `image` by `pattern` ({stem}: the image's name without suffix), beside it."""
    if "{stem}" not in pattern or "/" in pattern or not pattern.lower().endswith(".exr"):
        raise SolasError(f"depth pattern {pattern!r} must be a file name with {{stem}} ending in .exr, "
                         "e.g. {stem}_depth.exr (beside each image)")
    return image.with_name(pattern.replace("{stem}", image.stem))


def estimate(p: BatchPlan, workers: int) -> dict[str, float]:
    """Rough seconds and peak memory (bytes, all workers) of the items still to do."""
    from ..convolution.output import peak_bytes
    from ..imageio import image_size

    sizes = [(p.jobs[i].input, image_size(p.jobs[i].input)) for i in p.todo]
    values = [max(1, r * c * ch) for _, (r, c, ch) in sizes]
    if p.spec is None:
        grid_bytes = p.grid_path.stat().st_size  # float32 mosaics, stored uncompressed
    else:
        rows, cols = p.spec.grid
        grid_bytes = 4 * rows * cols * p.spec.size ** 2 * len(p.spec.wavelengths_nm or p.lens.wavelengths_nm) * len(
            p.spec.distances_m or [0])
    # each worker: its largest image's peak (which holds a grid; or its camera's); the parent holds one grid more
    per_worker = max((max(peak_bytes(path, r, c, ch, grid_bytes), camera_bytes(p.jobs[i], r, c))
                      for i, (path, (r, c, ch)) in zip(p.todo, sizes)), default=0.0)
    return {"seconds": SECONDS_PER_VALUE * sum(values) / min(workers, max(1, len(values))),
            "peak_bytes": min(workers, max(1, len(values))) * (per_worker + WORKER_BYTES["degrade"]) + grid_bytes,
            "grid_bytes": grid_bytes}


def camera_bytes(job: Job, rows: int, cols: int) -> float:
    """The peak memory of an item's camera stage (`sensor.commands.frame_bytes`, its RGB output read back;
    with the image processor when it writes a developed frame); 0 without a camera."""
    if not job.extras:
        return 0.0
    from ..isp.commands import DEVELOP_BYTES_PER_PIXEL
    from ..sensor.commands import frame_bytes

    return frame_bytes(rows, cols, 3, DEVELOP_BYTES_PER_PIXEL if len(job.extras) > 1 else 0.0)


def scaled_lens(lens, frame, pixel_um: float | None, spec=None) -> tuple[Any, dict | None]:
    """The batch's lens scaled to the frames' camera (`optics.scale.scaled_to_focal`: its pinhole focal
    length over the grid's x field range (`spec`, a GridSpec; None: the lens's field) the camera's focal
    length in pixels × `pixel_um`) and what was done; unchanged (and None) without `pixel_um`."""
    if pixel_um is None:
        return lens, None
    from ..optics.lens import Lens
    from ..optics.scale import scaled_to_focal

    if lens is None:
        raise SolasError("scaling the lens (--scale-lens) needs the lens the grid is computed from: give --lens, "
                         "not --psf-grid")
    if frame is None:
        raise SolasError("scaling the lens (--scale-lens) needs the frames' camera: give --intrinsics or --fisheye")
    lens = lens if isinstance(lens, Lens) else Lens.load(str(lens))
    field = spec.field_range_deg[0] if spec is not None and spec.field_range_deg else lens.field_deg
    sensor = spec is not None and spec.layout == "sensor"  # no pinhole: the paraxial image scale
    return scaled_to_focal(lens, frame.focal_px(), pixel_um, None if sensor or not field else field)


def degrade_batch(inputs: Iterable[str | os.PathLike], output_dir: str | os.PathLike, *,
                  psf_grid: str | os.PathLike | None = None, lens=None, grid_spec=None, method: str = "interp", boundary: str = "edge", linear: bool = False, workers: int | None = None,
                  dask: str | None = None, cache: GridCache | str | os.PathLike | None = None, force: bool = False,
                  progress: bool = True, output_format: str = "exr", depth_pattern: str | None = None,
                  occlusion: str = "filled", frame=None, scale_lens: float | None = None,
                  silhouette: str = "nearest", camera=None) -> BatchResult:
    """Degrade every image of `inputs` (files, folders, glob patterns) into `output_dir` (one EXR +
    PNG per input, `batch.json` beside them) with the grid `psf_grid` (an EXR file) or one computed
    from `lens` (a Lens or its name / file) with `grid_spec` (a `psf.spec.GridSpec`; default: its
    defaults), cached in `cache` (a GridCache or folder). `workers` local processes (default:
    the cores), or the Dask scheduler at `dask` ("local": a LocalCluster for this batch). An item
    that fails is recorded and the others go on. `output_format`: float or half EXR
    (`convolution.output.OUTPUT_FORMATS`). `depth_pattern` (e.g. "{stem}_depth.exr"): each image's
    depth map beside it, with a grid over object distance (`degrade --depth`, `occlusion`, `silhouette`). `frame`: the
    camera every input was taken with (`optics.frame.FrameCamera`, as `degrade`'s); `scale_lens`: that
    camera's pixel pitch (µm), the lens scaled to its focal length (`scaled_lens`), stated in the metadata. `camera`: each
    degraded frame (its values read as W/m²) through a sensor and image processor (`isp.camera.Camera`),
    its RAW and developed frame beside it (`<name>_raw.exr`, `<name>_raw.png`)."""
    from ..budget import check_memory
    from ..psf.depth import read_grid

    start = time.perf_counter()
    check_dask(dask)
    n = check_workers(workers, dask)
    cache = cache if isinstance(cache, GridCache) or psf_grid is not None else GridCache(cache)
    lens, scale = scaled_lens(lens, frame, scale_lens, grid_spec)
    p = plan_batch(inputs, output_dir, psf_grid=psf_grid, lens=lens, grid_spec=grid_spec, method=method,
                   boundary=boundary, linear=linear, cache=cache, output_format=output_format,
                   depth_pattern=depth_pattern, frame=frame, depth_options=(occlusion, silhouette), camera=camera)
    need = estimate(p, n if dask is None else 1)
    check_memory(f"batch of {len(p.todo)} images on {n} workers", need["peak_bytes"], force)
    from ..convolution.output import OUTPUT_FORMATS
    from ..progress import Progress

    if output_format not in OUTPUT_FORMATS:
        raise SolasError(f"output format {output_format!r} must be one of {', '.join(OUTPUT_FORMATS)}")
    header: dict[str, Any] = {"method": method, "boundary": boundary, "linear": linear, "format": output_format,
                              **({"frame_camera": asdict(frame)} if frame is not None else {}),
                              **({"lens_scale": scale} if scale is not None else {}),
                              **({"camera": camera.describe()} if camera is not None else {})}
    if p.lens is not None:
        with Progress("psf-grid", None, "PSFs", enabled=progress) as bar:  # shown only when it is computed
            p.grid_path, hit, seconds = cache.get(p.lens, p.spec, progress=bar)
        header["grid_source"], header["grid_seconds"] = "cache hit" if hit else "computed", seconds
        header["grid_spec"] = p.spec.canonical()
    else:
        header["grid_source"] = "given"
    grid = read_grid(str(p.grid_path))
    header.update({"psf_grid": str(p.grid_path), "grid_hash": file_hash(p.grid_path),
                   "lens": grid.meta.get("lens"), "lens_hash": grid.meta.get("lens_hash"),
                   "runner": {"dask": dask} if dask is not None else {"workers": n}})
    p.manifest.header.update(header)
    settings = {"method": method, "boundary": boundary, "linear": linear, "force": force, "format": output_format,
                "occlusion": occlusion, "silhouette": silhouette, "frame": frame, "camera": camera,
                "batch": {"id": p.key, "manifest": str(p.manifest.path), "grid_hash": header["grid_hash"],
                          "lens_hash": header["lens_hash"], **({"lens_scale": scale} if scale else {})}}
    from .runner import run_batch

    run_batch(p.manifest, p.todo, grid, str(p.grid_path), settings, n, dask, "image" if progress else None)
    return BatchResult(p.jobs, p.manifest.path, p.grid_path, header["grid_source"], time.perf_counter() - start)
