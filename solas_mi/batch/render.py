"""A batch of renders through a lens: images (the lens's image-object scene) and Mitsuba scene files
(the lens camera in place of the scene's camera), each at every point of a sweep over lenses, focus
distances, sensors, pixel pitches and samples per pixel: `render_batch` (the work) and
`plan_render` (what a run would do, for --dry-run).

The items are the product inputs × lenses × focus distances × sensors × pitches × spp; an output's
name is its input's stem followed by the value of each swept parameter (one given more than one
value), e.g. `street_solas-doublet_focus1000_spp64.exr`. Each item's seed is derived from its name
and the batch's base seed, so a re-run, another worker or Dask render it identically; the seed and
the sweep point are in the manifest and in the EXR's metadata. No PSF grid is computed.

Mitsuba variant (`render.mitsuba.variant_for`): the spectral JIT variant for every item, also at a
response of one wavelength (mono:λ): the mono variant is measured no faster (images render in
solas-mi's loop, which takes the same CPU time in mono; scene files render 1.5× slower in mono on the
street scene, `benchmarks/bench_mono.py`), and it turns a scene file's RGB and spectral data into
luminance instead of evaluating them at λ. A `variant` given is used for every item: a mono one
needs a response of one wavelength, and renders images exactly as the spectral one, scene files
alike only where their spectra are grey. The manifest's header and each EXR record the variant.
"""
from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Sequence

from ..errors import SolasError
from .degrade import BatchResult, check_dask, check_workers
from .jobs import IMAGE_SUFFIXES, MANIFEST, Job, Manifest, expand_inputs
from .work import SCENE_SUFFIXES

SWEEP = ("lens", "focus_distance", "sensor", "pitch_um", "spp")
SEEDS = 4096  # seeds 0…4095: the render passes' seeds (seed·1000003 + pass) stay within 32 bits


@dataclass
class RenderPlan:
    """What a render batch will do: its items (skipped ones marked) and the batch's identity."""

    jobs: list[Job]
    manifest: Manifest
    key: str

    @property
    def todo(self) -> list[int]:
        return [i for i, job in enumerate(self.jobs) if job.status != "skipped"]


def _values(name: str, given) -> list:
    values = list(given) if isinstance(given, (list, tuple)) else [given]
    if not values:
        raise SolasError(f"{name} needs at least one value")
    return values


def _focus(value) -> float | None:
    """A focus distance (world units of the scene; "inf" for infinity), or None: the lens file's."""
    if value is None:
        return None
    try:
        d = float(value)
    except (TypeError, ValueError):
        d = -1.0
    if not d > 0:
        raise SolasError(f"focus distance {value!r} must be a positive number of world units or inf")
    return d


def _sensor(value) -> tuple[int, int]:
    """(rows, columns) from "COLSxROWS" or a (rows, columns) pair."""
    from ..options import parse_wxh

    return tuple(int(v) for v in value) if isinstance(value, (list, tuple)) else parse_wxh(str(value), "--sensor")


def _label(name: str, value, lens_names: dict[str, str]) -> str:
    if name == "lens":
        return lens_names[value]
    if name == "focus_distance":
        return "focus" + ("inf" if math.isinf(value) else f"{value:g}")
    if name == "sensor":
        return f"{value[1]}x{value[0]}"
    if name == "pitch_um":
        return f"pitch{value:g}um"
    return f"spp{value}"


def seed_of(name: str, base_seed: int) -> int:
    """The seed of the item named `name` (its output's stem) in a batch of base seed `base_seed`."""
    digest = hashlib.sha256(f"{base_seed}:{name}".encode()).digest()
    return int.from_bytes(digest[:4], "little") % SEEDS


def plan_render(inputs: Iterable[str | os.PathLike], output_dir: str | os.PathLike, *, lens, focus_distance=None,
                sensor="1280x960", pitch_um=None, spp=64, response: str = "srgb", fov_deg: float | None = None,
                boundary: str = "edge", fresnel: str = "transmit", seed: int = 0) -> RenderPlan:
    """Check everything a render batch needs before any work and find what a former run finished.
    `lens`, `focus_distance`, `sensor`, `pitch_um` and `spp` are one value or a list of values (the
    sweep)."""
    from ..optics.lens import Lens
    from ..outputs import output_folder
    from ..render import response as responses

    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2 ** 31:
        raise SolasError(f"seed {seed!r} must be a whole number from 0 to 2^31 - 1")
    out_dir = output_folder(output_dir).resolve()
    files = expand_inputs(inputs, IMAGE_SUFFIXES + SCENE_SUFFIXES)
    lenses = {str(v): Lens.load(str(v)) for v in _values("lens", lens)}
    for one in lenses.values():
        responses.check_lens(responses.parse(response, one.wavelengths_nm), one)
    axes = {"lens": list(lenses), "focus_distance": [_focus(v) for v in _values("focus distance", focus_distance)],
            "sensor": [_sensor(v) for v in _values("sensor", sensor)],
            "pitch_um": [None if v is None else float(v) for v in _values("pitch", pitch_um)],
            "spp": _values("spp", spp)}
    for n in axes["spp"]:
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 1 << 20:
            raise SolasError(f"samples per pixel {n!r} must be a whole number from 1 to {1 << 20}")
    scenes = [f for f in files if f.suffix.lower() in SCENE_SUFFIXES]
    if axes["focus_distance"] != [None] and len(scenes) < len(files):
        raise SolasError("a focus distance sets the lens camera of scene files; image inputs lie on the lens's "
                         "object plane: give them without --focus-distance, or as a separate batch")
    if len(axes["sensor"]) > 1 and scenes:
        raise SolasError("a scene file's film sets its sensor; sweep --sensor over image inputs only")
    swept = [name for name in SWEEP if len(axes[name]) > 1]
    names = {k: v.name for k, v in lenses.items()}
    jobs, seen, sources = [], {}, set(files)
    for path, point in itertools.product(files, itertools.product(*(axes[name] for name in SWEEP))):
        params = dict(zip(SWEEP, point))
        stem = "_".join([path.stem, *(_label(name, params[name], names) for name in swept)])
        output = out_dir / f"{stem}.exr"
        if output in seen:
            raise SolasError(f"inputs {str(seen[output])!r} and {str(path)!r} would both write {output}; "
                             "give them different names or run them as separate batches")
        if output in sources or output.with_suffix(".png") in sources:
            raise SolasError(f"output {output} would replace an input of the same name; choose another -o")
        seen[output] = path
        one = lenses[params["lens"]]
        params.update(lens_name=one.name, lens_hash=one.hash, response=response, sensor=list(params["sensor"]))
        if params["focus_distance"] is not None and math.isinf(params["focus_distance"]):
            params["focus_distance"] = "inf"  # JSON has no infinity; Mitsuba reads "inf"
        jobs.append(Job(str(path), str(output), str(output.with_suffix(".png")), kind="render",
                        seed=seed_of(stem, seed), params=params))
    # the settings every item shares; each item is matched on its input, output and sweep point, so a
    # sweep grown by a value redoes only the new items
    key = hashlib.sha256(json.dumps(["render", fov_deg, boundary, fresnel, seed]).encode()).hexdigest()[:16]
    manifest = Manifest(out_dir / MANIFEST, {"version": 1, "kind": "render", "batch_id": key,
                                             "sweep": {name: axes[name] for name in swept}}, jobs)
    manifest.resume(key)
    return RenderPlan(jobs, manifest, key)


def estimate(p: RenderPlan, workers: int) -> dict[str, float]:
    """Rough seconds and peak memory (bytes, all workers) of the items still to do."""
    from ..render.commands import BYTES_PER_SAMPLE, SAMPLES_PER_SECOND_PER_CORE
    from ..render.stock import SAMPLES_PER_PASS
    from ..render.user_scene import scene_film_size

    samples, peak = 0, 0
    for i in p.todo:
        job = p.jobs[i]
        if Path(job.input).suffix.lower() in SCENE_SUFFIXES:
            try:
                cols, rows = scene_film_size(job.input)
            except SolasError:  # the item will fail on its own; it costs nothing
                continue
        else:
            rows, cols = job.params["sensor"]
        samples += rows * cols * job.params["spp"]
        peak = max(peak, max(rows * cols, SAMPLES_PER_PASS) * BYTES_PER_SAMPLE + 48 * rows * cols)
    cores = os.cpu_count() or 1
    return {"seconds": samples / (SAMPLES_PER_SECOND_PER_CORE * cores), "samples": samples,
            "peak_bytes": min(workers, max(1, len(p.todo))) * peak}


def batch_variant(lens, response: str, variant: str | None) -> str:
    """The Mitsuba variant of a batch's items (`render.mitsuba.variant_for`): `variant` when given,
    SolasError unless it serves the response of every lens of `lens`; else the spectral one."""
    from ..optics.lens import Lens
    from ..render import response as responses
    from ..render.mitsuba import variant_for

    parsed = [responses.parse(response, Lens.load(str(v)).wavelengths_nm) for v in _values("lens", lens)]
    return ", ".join(sorted({variant_for(r, variant) for r in parsed}))


def render_batch(inputs: Iterable[str | os.PathLike], output_dir: str | os.PathLike, *, lens: str | Sequence[str],
                 focus_distance=None, sensor="1280x960", pitch_um=None, spp=64, response: str = "srgb",
                 fov_deg: float | None = None, boundary: str = "edge", fresnel: str = "transmit", seed: int = 0,
                 variant: str | None = None, workers: int | None = None, dask: str | None = None,
                 force: bool = False, progress: bool = True) -> BatchResult:
    """Render every input of `inputs` (images and Mitsuba scene XML files: files, folders, glob
    patterns) through `lens` (a shipped name or .toml file) into `output_dir` (one EXR + PNG per item,
    `batch.json` beside them), at every point of the sweep: `lens`, `focus_distance` (scene units;
    scenes only), `sensor` ("COLSxROWS"; images only), `pitch_um` (µm) and `spp` each take one value
    or a list. `response`, `fov_deg`, `boundary`, `fresnel` as in `render.image.render_image`; `seed`
    the batch's base seed. `workers` local processes (default: the cores), or the Dask scheduler at
    `dask` ("local": a LocalCluster for this batch). A failed item is recorded; the others go on."""
    from ..budget import check_memory
    from .runner import run_batch

    start = time.perf_counter()
    n = check_workers(workers)
    check_dask(dask)
    p = plan_render(inputs, output_dir, lens=lens, focus_distance=focus_distance, sensor=sensor, pitch_um=pitch_um,
                    spp=spp, response=response, fov_deg=fov_deg, boundary=boundary, fresnel=fresnel, seed=seed)
    check_memory(f"batch of {len(p.todo)} renders on {n} workers", estimate(p, n if dask is None else 1)["peak_bytes"],
                 force)
    chosen = batch_variant(lens, response, variant)
    # each local worker (and each Dask worker of a LocalCluster) gets its share of the cores, so that
    # the local and the Dask runs render with the same thread count (identical sums)
    threads = max(1, (os.cpu_count() or 1) // n) if dask in (None, "local") else None
    p.manifest.header.update({"variant": chosen, "response": response, "fov_deg": fov_deg, "boundary": boundary,
                              "fresnel": fresnel, "seed": seed, "threads_per_worker": threads,
                              "runner": {"dask": dask} if dask is not None else {"workers": n}})
    settings = {"variant": variant, "fov_deg": fov_deg, "boundary": boundary, "fresnel": fresnel, "threads": threads,
                "batch": {"id": p.key, "manifest": str(p.manifest.path)}}
    run_batch(p.manifest, p.todo, None, None, settings, n, dask, "render" if progress else None)
    return BatchResult(p.jobs, p.manifest.path, None, "none", time.perf_counter() - start)
