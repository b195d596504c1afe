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
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import SolasError
from .cache import GridCache, file_hash
from .jobs import MANIFEST, SCENE_SUFFIXES, Job, Manifest, add_outputs, expand_inputs, plan, say_skipped
from .runner import check_dask

if TYPE_CHECKING:
    from ..convolution.spec import DegradeSpec

# seconds per image value (H·W·C) on one core of the 2-core benchmark machine, reading, degrading
# (interp) and writing included (benchmarks/bench_batch.py: 1280×960 RGB, 32×32 grid)
SECONDS_PER_VALUE = 2.0e-7
# a worker process's own memory before its first item (VmRSS of a spawned process with the modules an
# item imports, measured: degrade — numpy, OpenEXR, the convolution — 37 MB; render — Mitsuba with its
# spectral variant set — 110 MB), added to each worker's items' peak in the estimates
WORKER_BYTES = {"degrade": 37e6, "render": 110e6}


@dataclass
class BatchPlan:
    """What a batch will do: its items (skipped ones marked), how it degrades them, the grid and where
    it comes from."""

    jobs: list[Job]
    manifest: Manifest
    key: str  # the batch's identity: the grid and what the outputs depend on (`DegradeSpec.identity`)
    spec: DegradeSpec
    grid_path: Path
    grid_source: str  # "given", "cache hit" or "to compute"
    lens: Any = None  # the lens the grid is computed from (scaled to the frames' camera if asked)
    grid_spec: Any = None  # the grid's `psf.spec.GridSpec` when computed from the lens
    cache: GridCache | None = None  # where that grid is kept
    lens_scale: dict | None = None  # what scaling the lens did (`scaled_lens`), or None
    population: tuple | None = None  # a lens population (`population.Population`, its (lens file, Lens)), or None
    grid_hash: str | None = None  # a given grid file's `file_hash` (hashed once: 0.2 CPU-s for a 315 MB grid)

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


def plan_batch(inputs: Iterable[str | os.PathLike], output_dir: str | os.PathLike, spec: DegradeSpec | None = None, *,
               psf_grid: str | os.PathLike | None = None, lens=None,
               cache: GridCache | str | os.PathLike | None = None, lens_population=None) -> BatchPlan:
    """Check everything a batch needs before any work and find what a former run finished: the items of
    `inputs` degraded into `output_dir` as `spec` says (a `convolution.spec.DegradeSpec`; None: its
    defaults) by the grid file `psf_grid`, the grid of `lens` (scaled as `spec.scale_lens` says) and
    `spec.grid_spec`, kept in `cache` (a GridCache or folder; None: the user's), or each item's own lens of
    `lens_population` (a folder or a `population.Population`: seed and temperatures)."""
    from ..convolution.spec import OUTPUT_FILES, DegradeSpec
    from ..outputs import output_folder
    from . import population as pop

    spec = DegradeSpec() if spec is None else spec
    if not isinstance(spec, DegradeSpec):
        raise SolasError(f"spec {spec!r} must be a solas_mi.convolution.spec.DegradeSpec")
    population = pop.checked(lens_population, psf_grid, lens, spec.scale_lens)
    if psf_grid is not None and spec.grid_spec is not None:
        raise SolasError("grid_spec is for a grid computed from a lens; a PSF grid file given is used as it is")
    lens, scale = scaled_lens(lens, spec)
    out_dir = output_folder(output_dir).resolve()
    roots: dict[Path, Path] = {}  # folders are read as trees, their structure kept in the output folder
    labels: list[tuple[Path, str]] = []
    files = expand_inputs(inputs, roots=roots, skipped=labels)
    patterns = {**({"depth map": spec.depth_pattern} if spec.depth_pattern is not None else {}),
                **dict(spec.label_patterns or ())}
    beside = {f: {what: beside_file(f, pattern) for what, pattern in patterns.items()} for f in files}
    theirs = {path for f, found in beside.items() for path in found.values() if path != f}  # a frame may hold its own
    images = [f for f in files if f not in theirs]  # depth maps and label files are no inputs
    say_skipped([(f, why) for f, why in labels if f not in theirs])  # those not the frames' own
    for what, pattern in patterns.items():
        missing = [str(beside[f][what]) for f in images if not beside[f][what].is_file()]
        if missing:
            noun = what if what == "depth map" else f"{what} labels"
            raise SolasError(f"{len(missing)} image(s) have no {noun} by the pattern {pattern!r}, e.g. {missing[0]}")
    jobs = plan(images, out_dir, roots, OUTPUT_FILES[spec.output_format])
    with_labels(jobs, spec.label_patterns, files, spec.ghosts)
    with_camera(jobs, spec.camera, files, spec.output_format)
    for job in jobs:
        found = beside[Path(job.input)]
        if "depth map" in found:
            job.params["depth"] = str(found["depth map"])
        if spec.label_patterns:
            job.params["labels"] = {kind: str(found[kind]) for kind, _ in spec.label_patterns}
    lens = population[1][0][1] if population is not None else lens
    grid_path, source, lens, grid_spec, cache = _grid_source(psf_grid, lens, spec.grid_spec, cache)
    grid_hash = file_hash(grid_path) if source == "given" else None
    grid_id = grid_hash or grid_path.stem
    if population is not None:  # the first lens's cache name stands for the grid options
        (given, lenses), source = population, "population"
        pop.assign(jobs, lenses, given.seed, given.temperatures_c, cache, grid_spec)
        grid_id, grid_path = f"{pop.key(lenses, given.seed, given.temperatures_c)}-{grid_id}", Path(given.folder)
    key = hashlib.sha256(json.dumps([grid_id, *spec.identity()]).encode()).hexdigest()[:16]
    manifest = Manifest(out_dir / MANIFEST, {"version": 1, "kind": "degrade", "batch_id": key}, jobs)
    manifest.resume(key)
    return BatchPlan(jobs, manifest, key, spec, grid_path, source, lens, grid_spec, cache, scale, population, grid_hash)


def _grid_source(psf_grid, lens, grid_spec, cache) -> tuple[Path, str, Any, Any, GridCache | None]:
    """The batch's grid file, where it comes from ("given", "cache hit", "to compute") and, computed from
    `lens` (a Lens or its name / file), the Lens, its GridSpec (`grid_spec`, None: the defaults) and the
    GridCache."""
    if psf_grid is not None:
        grid_path = Path(psf_grid).resolve()
        if not grid_path.is_file():
            raise SolasError(f"PSF grid {str(psf_grid)!r} is not a file; give an EXR written by `solas-mi psf-grid`")
        return grid_path, "given", None, None, None
    from ..optics.lens import Lens
    from ..psf.spec import GridSpec

    lens = lens if isinstance(lens, Lens) else Lens.load(str(lens))
    cache = cache if isinstance(cache, GridCache) else GridCache(cache)
    grid_spec = GridSpec() if grid_spec is None else grid_spec
    grid_path = cache.path(lens, grid_spec)
    hit = grid_path.is_file() and cache.check(grid_path, lens, grid_spec) is None
    return grid_path, "cache hit" if hit else "to compute", lens, grid_spec, cache


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
    images = [str(f) for f in sources if Path(f).suffix.lower() not in SCENE_SUFFIXES]
    if camera.scene_timing is not None and images:  # --pwm-emitter, --camera-motion: a scene file's
        raise SolasError(f"the camera's PWM emitters and camera motion are a scene file's; {images[0]} is an image: "
                         "give the images as a separate batch")
    add_outputs(jobs, lambda output: camera_outputs(output, camera), sources)


def beside_file(image: Path, pattern: str) -> Path:
    """The file of `image` by `pattern` (its depth map, a label file; {stem}: the image's name without
    suffix; a pattern `DegradeSpec` checked), beside it."""
    return image.with_name(pattern.replace("{stem}", image.stem))


def with_labels(jobs: list[Job], patterns, sources, flare: bool = False) -> None:
    """The warped labels' files (`convolution.labels.label_outputs`) added to each item, and with `flare` (ghosts)
    the flare label's; none without either."""
    if patterns or flare:
        from ..convolution.labels import label_outputs

        kinds = [kind for kind, _ in patterns or ()]
        add_outputs(jobs, lambda output: [str(p) for p in label_outputs(output, kinds, flare).values()], sources,
                    "label_outputs")


def estimate(p: BatchPlan, workers: int) -> dict[str, float]:
    """Rough seconds and peak memory (bytes, all workers) of the items still to do."""
    from ..convolution.camera import fit_bytes
    from ..convolution.labels import memory_bytes
    from ..convolution.output import peak_bytes
    from ..imageio import image_size

    sizes = [(p.jobs[i].input, image_size(p.jobs[i].input)) for i in p.todo]
    values = [max(1, r * c * ch) for _, (r, c, ch) in sizes]
    g = p.grid_spec
    if g is None:
        grid_bytes = p.grid_path.stat().st_size  # float32 mosaics, stored uncompressed
    else:
        rows, cols = g.grid
        grid_bytes = 4 * rows * cols * g.size ** 2 * len(g.wavelengths_nm or p.lens.wavelengths_nm) * len(
            g.distances_m or [0])
    # each worker: its largest image's peak (which holds a grid; or its camera's)
    per_worker = max((max(peak_bytes(path, r, c, ch, grid_bytes, p.spec.ghosts) + memory_bytes(r * c, p.jobs[i].params.get("labels", ())),
                          camera_bytes(p.jobs[i], r, c, p.spec.camera)) for i, (path, (r, c, ch)) in zip(p.todo, sizes)), default=0.0)
    # the parent: one grid more, and its fits of the frames' camera blocks (`convolution.camera`)
    parent = grid_bytes + fit_bytes(max((r * c for _, (r, c, _) in sizes), default=0))
    return {"seconds": SECONDS_PER_VALUE * sum(values) / min(workers, max(1, len(values))),
            "peak_bytes": min(workers, max(1, len(values))) * (per_worker + WORKER_BYTES["degrade"]) + parent,
            "grid_bytes": grid_bytes}


def camera_bytes(job: Job, rows: int, cols: int, camera) -> float:
    """The peak memory of an item's stage through the batch's `camera` (`sensor.commands.frame_bytes`: its RGB
    output read back, the sensor's readouts, the camera's scene in time; with the image processor when it
    writes a developed frame); 0 without a camera."""
    if not job.extras or camera is None:
        return 0.0
    from ..isp.commands import DEVELOP_BYTES_PER_PIXEL
    from ..sensor.capture import as_chain
    from ..sensor.commands import frame_bytes

    return frame_bytes(
        rows,
        cols,
        3,
        DEVELOP_BYTES_PER_PIXEL if len(job.extras) > 1 else 0.0,
        len(as_chain(camera.sensor).readouts),
        camera.scene_in_time is not None,
    )


def batch_ghosts(grid, lens) -> str:
    """The ghost grid of the batch's `lens` (None: the grid's, `convolution.camera.grid_lens`) over the PSF grid's
    field, computed into the cache before the items (`convolution.ghosts.lens_ghosts`); the lens's name."""
    from ..convolution.camera import grid_lens
    from ..convolution.ghosts import lens_ghosts

    lens = grid_lens(grid) if lens is None else lens
    if lens is None:
        raise SolasError(f"ghosts: the PSF grid's lens {grid.meta.get('lens')!r} cannot be read again: give --lens")
    lens_ghosts(lens, getattr(grid, "layers", [grid])[0])
    return lens.name


def scaled_lens(lens, spec: DegradeSpec) -> tuple[Any, dict | None]:
    """The batch's lens scaled to the frames' camera `spec.frame` (`optics.scale.scaled_to_focal`: its
    pinhole focal length over the x field range of `spec.grid_spec` (None: the lens's field) the camera's
    focal length in pixels × `spec.scale_lens`) and what was done; unchanged (and None) without
    `spec.scale_lens`."""
    pixel_um, frame, grid = spec.scale_lens, spec.frame, spec.grid_spec
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
    field = grid.field_range_deg[0] if grid is not None and grid.field_range_deg else lens.field_deg
    sensor = grid is not None and grid.layout == "sensor"  # no pinhole: the paraxial image scale
    return scaled_to_focal(lens, frame.focal_px(), pixel_um, None if sensor or not field else field)


# long: the public API's numpydoc docstring is half of it
# many parameters: a batch's three exclusive sources (a grid file, a lens, a lens population) are keywords of their own
def degrade_batch(inputs: Iterable[str | os.PathLike], output_dir: str | os.PathLike, spec: DegradeSpec | None = None,
                  *, psf_grid: str | os.PathLike | None = None, lens=None, workers: int | None = None,
                  dask: str | None = None, cache: GridCache | str | os.PathLike | None = None, force: bool = False,
                  progress: bool = True, lens_population=None) -> BatchResult:
    """Degrade many images by one PSF grid, on local processes or a Dask cluster; resumable.

    One EXR + PNG per input (or as ``spec.output_format`` says) and the manifest ``batch.json`` go into
    `output_dir`. An item that fails is recorded and the others go on; a batch run again skips what a
    former run finished ([batch work](../details/batch.md)). A script that calls it needs the main guard
    (``if __name__ == "__main__":``): the workers are spawned processes.

    Parameters
    ----------
    inputs : iterable of str or PathLike
        Image files, folders and glob patterns.
    output_dir : str or PathLike
        Where the outputs go.
    spec : DegradeSpec, optional
        How (`convolution.spec.DegradeSpec`: method, boundary, depth maps, the frames' camera, a camera
        stage, the grid's options); default: its defaults.
    psf_grid : str or PathLike, optional
        A PSF grid's EXR file; or give `lens`.
    lens : Lens or str, optional
        A lens (or its name or file) whose grid is computed with ``spec.grid_spec`` and cached.
    lens_population : str, PathLike or population.Population, optional
        Instead: a folder of lens files (a `solas-mi tolerance` output), each item degraded by one of them,
        chosen by the Population's seed and the item's name, at one of its temperatures where given.
    workers : int, optional
        Local processes; default: the cores.
    dask : str, optional
        A Dask scheduler's address, or "local" (a LocalCluster for this batch), instead of local processes.
    cache : GridCache or str or PathLike, optional
        The grid cache or its folder; default: `cache.default_cache_dir()`.
    force : bool, default False
        Run even when the estimated memory exceeds what is free.
    progress : bool, default True
        Show progress on stderr.

    Returns
    -------
    BatchResult
        Its items (`jobs`, each with its status), the manifest's path, the grid's path and where it came
        from ("computed", "cache hit", "given").

    Raises
    ------
    SolasError
        For bad inputs, options, workers or scheduler, neither or both of a grid and a lens, or a batch that
        would not fit in memory.

    Examples
    --------
    >>> import numpy as np
    >>> from solas_mi.batch import degrade_batch
    >>> from solas_mi.convolution import DegradeSpec
    >>> from solas_mi.imageio import write_png
    >>> from solas_mi.psf import GridSpec
    >>> write_png("frame.png", np.full((48, 64, 3), 0.5, np.float32))
    >>> done = degrade_batch(["frame.png"], "degraded", DegradeSpec(grid_spec=GridSpec(grid=(2, 2), size=32)),
    ...                      lens="solas-doublet", workers=1, cache="grids", progress=False)
    >>> [job.status for job in done.jobs], done.grid_source
    (['done'], 'computed')
    """
    from ..budget import check_memory
    from ..convolution.camera import frame_cameras
    from ..imageio import image_size
    from ..progress import Progress
    from ..psf.depth import read_grid
    from .runner import run_batch

    start = time.perf_counter()
    check_dask(dask)
    n = check_workers(workers, dask)
    p = plan_batch(inputs, output_dir, spec, psf_grid=psf_grid, lens=lens, cache=cache,
                   lens_population=lens_population)
    need = estimate(p, n if dask is None else 1)
    check_memory(f"batch of {len(p.todo)} images on {n} workers", need["peak_bytes"], force)
    header = p.spec.header(p.lens_scale)
    if p.population is not None:
        from .population import degrade_settings

        settings = degrade_settings(p, header, n, dask, force, progress)
        run_batch(p.manifest, p.todo, None, None, settings, n, dask, "image" if progress else None)
        return BatchResult(p.jobs, p.manifest.path, None, "population", time.perf_counter() - start)
    if p.lens is not None:
        assert p.cache is not None  # a lens's grid is kept in the cache (_grid_source)
        with Progress("psf-grid", None, "PSFs", enabled=progress) as bar:  # shown only when it is computed
            p.grid_path, hit, seconds = p.cache.get(p.lens, p.grid_spec, progress=bar)
        header["grid_source"], header["grid_seconds"] = "cache hit" if hit else "computed", seconds
        header["grid_spec"] = p.grid_spec.canonical()
    else:
        header["grid_source"] = "given"
    grid = read_grid(str(p.grid_path))
    sizes = [image_size(job.input)[1::-1] for job in p.jobs]  # (0, 0): unreadable, the item will say why
    cameras = frame_cameras(grid, [s for s in sizes if s[0]], p.spec.frame, p.spec.calibration_model,
                            p.lens)  # one fit per frame size, here, not per frame
    header.update({"psf_grid": str(p.grid_path), "grid_hash": p.grid_hash or file_hash(p.grid_path),
                   "lens": grid.meta.get("lens"), "lens_hash": grid.meta.get("lens_hash"),
                   "cameras": cameras, "runner": {"dask": dask} if dask is not None else {"workers": n}})
    if p.spec.ghosts:  # the lens's ghost grid computed once here, each item reads it from the cache
        header["ghosts"]["lens"] = batch_ghosts(grid, p.lens)
    p.manifest.header.update(header)
    settings = {"spec": p.spec, "camera": p.spec.camera, "force": force, "cameras": cameras, "lens": p.lens,
                "batch": {"id": p.key, "manifest": str(p.manifest.path), "grid_hash": header["grid_hash"],
                          "lens_hash": header["lens_hash"], **({"lens_scale": p.lens_scale} if p.lens_scale else {})}}
    run_batch(p.manifest, p.todo, grid, str(p.grid_path), settings, n, dask, "image" if progress else None)
    return BatchResult(p.jobs, p.manifest.path, p.grid_path, header["grid_source"], time.perf_counter() - start)

