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
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import SolasError
from ..outputs import inside, safe_name
from ..render.spec import RenderSpec
from .degrade import WORKER_BYTES, BatchResult, camera_bytes, check_workers, with_camera
from .jobs import IMAGE_SUFFIXES, MANIFEST, SCENE_SUFFIXES, Job, Manifest, expand_inputs
from .population import Population, item_lens, loaded, pick
from .population import key as key_of
from .runner import check_dask, worker_threads

SWEEP = ("lens", "focus_distance", "sensor", "pitch_um", "spp")  # lens, then RenderSpec fields
SEEDS = 4096  # seeds 0…4095: the render passes' seeds (seed·1000003 + pass) stay within 32 bits
MAX_BASE_SEED = 2**31 - 1


@dataclass
class RenderPlan:
    """What a render batch will do: its items (skipped ones marked) and the batch's identity; `spec`
    the settings every item shares (its sweep fields at their first values, its seed the batch's base)."""

    jobs: list[Job]
    manifest: Manifest
    key: str
    spec: RenderSpec
    camera: Any = None  # the batch's camera (`isp.camera.Camera`), or None

    @property
    def todo(self) -> list[int]:
        return [i for i, job in enumerate(self.jobs) if job.status != "skipped"]


def _values(name: str, given) -> list:
    values = list(given) if isinstance(given, (list, tuple)) and not (name == "sensor" and _is_pair(given)) else [given]
    if not values:
        raise SolasError(f"{name} needs at least one value")
    return values


def _is_pair(value) -> bool:
    """A (rows, columns) pair of integers: one sensor, not a list of sensors."""
    return len(value) == 2 and all(isinstance(v, int) for v in value)


def _label(name: str, value, lens_names: dict[str, str]) -> str:
    if name == "lens":
        return safe_name(lens_names[value], "lens")
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


def batch_spec(spec: RenderSpec | None, settings: dict[str, Any]) -> tuple[RenderSpec, dict[str, list]]:
    """The batch's shared RenderSpec (`spec` with `settings` changed; a sweep field given a list holds
    its first value) and the values of each sweep field (checked, each as the spec holds it)."""
    base = spec or RenderSpec()
    axes = {name: _values(name.replace("_", " "), settings.pop(name, getattr(base, name))) for name in SWEEP[1:]}
    base = base.replace(**settings, **{name: values[0] for name, values in axes.items()})
    if not 0 <= base.seed <= MAX_BASE_SEED:
        raise SolasError(f"seed {base.seed!r} must be a whole number from 0 to 2^31 - 1")
    return base, {name: [getattr(base.replace(**{name: v}), name) for v in values] for name, values in axes.items()}


def _check_inputs(files: list[Path], base: RenderSpec, axes: dict[str, list]) -> None:
    """Refuse a sweep that does not apply to the inputs given."""
    scenes = [f for f in files if f.suffix.lower() in SCENE_SUFFIXES]
    for given, what, flag in (
        (axes["focus_distance"] != [None], "a focus distance sets", "--focus-distance"),
        (bool(base.labels), "labels are traced through", "--labels"),
    ):
        if given and len(scenes) < len(files):
            raise SolasError(
                f"{what} the lens camera of scene files; image inputs lie on the lens's object plane: "
                f"give them without {flag}, or as a separate batch"
            )
    if len(axes["sensor"]) > 1 and scenes:
        raise SolasError("a scene file's film sets its sensor; sweep --sensor over image inputs only")


def _jobs(
    files: list[Path], out_dir: Path, base: RenderSpec, axes: dict[str, list], lenses: dict, population=None
) -> list[Job]:
    """One item per input and sweep point, named by its input and swept values, seeded by its name; with a
    lens `population` (`population.Population`), its lens (and temperature) picked by the seed and that name."""
    swept = [name for name in SWEEP if len(axes[name]) > 1]
    names = {k: v.name for k, v in lenses.items()}
    jobs, sources = [], set(files)
    seen: dict[Path, Path] = {}  # output → the input that writes it
    for path, point in itertools.product(files, itertools.product(*(axes[name] for name in SWEEP))):
        values = dict(zip(SWEEP, point))
        stem = safe_name("_".join([safe_name(path.stem), *(_label(name, values[name], names) for name in swept)]))
        output = inside(out_dir, f"{stem}.exr")
        if output in seen:
            raise SolasError(
                f"inputs {str(seen[output])!r} and {str(path)!r} would both write {output}; "
                "give them different names or run them as separate batches"
            )
        if output in sources or output.with_suffix(".png") in sources:
            raise SolasError(f"output {output} would replace an input of the same name; choose another -o")
        seen[output] = path
        lens, own = values.pop("lens"), {}
        if population is not None:  # `population.pick`: the lens file and its temperature
            own = pick(stem, list(lenses.items()), population.seed, population.temperatures_c)
            lens = own.pop("file")
        item = base.replace(**values, seed=seed_of(stem, base.seed))
        chosen = own.pop("lens") if own else lenses[lens]
        params = {"lens": lens, "lens_name": chosen.name, "lens_hash": chosen.hash, **item.as_dict()}
        params.update({"lens_index": own["index"], "temperature_c": own["temperature_c"]} if own else {})
        jobs.append(
            Job(str(path), str(output), str(output.with_suffix(".png")), kind="render", seed=item.seed, params=params)
        )
    return jobs


def plan_render(
    inputs: Iterable[str | os.PathLike],
    output_dir: str | os.PathLike,
    *,
    lens,
    spec: RenderSpec | None = None,
    camera=None,
    **settings,
) -> RenderPlan:
    """Check everything a render batch needs before any work and find what a former run finished.
    `lens` is one value or a list (the sweep), or a `population.Population` (each item's lens picked by its
    seed and the item's name); `settings` are RenderSpec fields changing `spec`, of
    which `focus_distance`, `sensor`, `pitch_um` and `spp` also take a list of values (the sweep);
    `seed` is the batch's base seed (each item's derives from it and the item's name)."""
    from ..optics.lens import Lens
    from ..outputs import output_folder
    from ..render import response as responses

    base, axes = batch_spec(spec, settings)
    out_dir = output_folder(output_dir).resolve()
    files = expand_inputs(inputs, IMAGE_SUFFIXES + SCENE_SUFFIXES)
    population, members = loaded(lens) if isinstance(lens, Population) else (None, [])
    lenses: dict[str, Any] = dict(members) or {str(v): Lens.load(str(v)) for v in _values("lens", lens)}
    for one in lenses.values():
        responses.check_lens(responses.parse(base.response, one.wavelengths_nm), one)
    axes["lens"] = list(lenses) if population is None else [None]  # a population's: picked per item
    _check_inputs(files, base, axes)
    jobs = _jobs(files, out_dir, base, axes, lenses, population)
    with_camera(jobs, camera, files)
    if base.labels and camera is not None and camera.scene_timing is not None:
        raise SolasError(
            "--labels are traced at one pose of the camera, a camera's PWM emitters and camera motion render the "
            "frame over its exposure windows: give them as separate batches"
        )
    # the settings every item shares; each item is matched on its input, output and sweep point, so a
    # sweep grown by a value redoes only the new items
    shared = {k: v for k, v in base.as_dict().items() if k not in SWEEP}
    if camera is not None:
        shared["camera"] = camera.describe()
    if population is not None:
        shared["lens_population"] = key_of(list(lenses.items()), population.seed, population.temperatures_c)
    key = hashlib.sha256(json.dumps(["render", shared]).encode()).hexdigest()[:16]
    sweep = {name: _json_axis(name, axes[name]) for name in SWEEP if len(axes[name]) > 1}
    manifest = Manifest(out_dir / MANIFEST, {"version": 1, "kind": "render", "batch_id": key, "sweep": sweep}, jobs)
    manifest.resume(key)
    return RenderPlan(jobs, manifest, key, base, camera)


def _json_axis(name: str, values: list) -> list:
    """A sweep axis as the manifest holds it (the items' form: sensors as lists, infinity as "inf")."""
    if name == "lens":
        return values
    return [RenderSpec().replace(**{name: v}).as_dict()[name] for v in values]


def estimate(p: RenderPlan, workers: int) -> dict[str, float]:
    """Rough seconds and peak memory (bytes, all workers) of the items still to do."""
    from ..render.commands import BYTES_PER_SAMPLE, SAMPLES_PER_SECOND_PER_CORE
    from ..render.stock import SAMPLES_PER_PASS
    from ..render.user_scene import scene_film_size

    samples = 0
    peak: float = 0
    timing = None if p.camera is None else p.camera.scene_timing  # its scene items rendered in parts over the frame
    shutter = None
    if timing is not None:
        from ..sensor.capture import as_chain

        shutter = as_chain(p.camera.sensor).shutter
    parts = 1 if timing is None else timing.parts(shutter)

    def timed(rows: int, cols: int) -> float:
        return 0.0 if timing is None else timing.parts_bytes(shutter, rows, cols)

    for i in p.todo:
        job = p.jobs[i]
        if Path(job.input).suffix.lower() in SCENE_SUFFIXES:
            try:
                cols, rows = scene_film_size(job.input)
            except SolasError:  # the item will fail on its own; it costs nothing
                continue
        else:
            rows, cols = job.params["sensor"]
        samples += rows * cols * job.params["spp"] * parts
        peak = max(
            peak,
            max(rows * cols, SAMPLES_PER_PASS) * BYTES_PER_SAMPLE + 48 * rows * cols + timed(rows, cols),
            camera_bytes(job, rows, cols, p.camera),
        )
    cores = os.cpu_count() or 1
    return {
        "seconds": samples / (SAMPLES_PER_SECOND_PER_CORE * cores),
        "samples": samples,
        "peak_bytes": min(workers, max(1, len(p.todo))) * (peak + WORKER_BYTES["render"]),
    }


def batch_variant(p: RenderPlan) -> str:
    """The Mitsuba variant of a batch's items (`render.mitsuba.variant_for`): the spec's variant when
    given, SolasError unless it serves the response of every lens of the batch; else the spectral one."""
    from ..optics.lens import Lens
    from ..render import response as responses
    from ..render.mitsuba import variant_for

    hashes = {job.params["lens"]: None for job in p.jobs}
    parsed = [responses.parse(p.spec.response, Lens.load(name).wavelengths_nm) for name in hashes]
    return ", ".join(sorted({variant_for(r, p.spec.variant) for r in parsed}))


def image_cameras(p: RenderPlan, model: str | None) -> dict[str, dict]:
    """The camera block (`render.image.image_camera`) of each sensor the batch's image items render onto,
    fitted once per lens, sensor and wavelength, before any item: `image_sensor_key` → block ({} without a
    model). A scene file's camera comes from its scene (`batch.work`)."""
    from ..render.image import image_camera, image_sensor_key

    out: dict[str, dict] = {}
    if model is None:
        return out
    lenses: dict[str, Any] = {}
    for job in p.jobs:
        if Path(job.input).suffix.lower() in SCENE_SUFFIXES:
            continue
        which = f"{job.params['lens']}@{job.params.get('temperature_c')}"
        if which not in lenses:
            lenses[which] = item_lens(job.params)
        lens = lenses[which]
        key, camera, response = image_sensor_key(lens, RenderSpec.from_dict(job.params))
        if key not in out:
            out[key] = image_camera(lens, camera, response, model)
    return out


# long: the public API's numpydoc docstring is half of it
# many parameters: the inputs, lens and spec, the runner's settings and what every output records (camera, calibration)
def render_batch(
    inputs: Iterable[str | os.PathLike],
    output_dir: str | os.PathLike,
    *,
    lens: str | Sequence[str],
    spec: RenderSpec | None = None,
    workers: int | None = None,
    dask: str | None = None,
    force: bool = False,
    progress: bool = True,
    camera=None,
    calibration_model: str | None = None,
    **settings,
) -> BatchResult:
    """Render many images and scene files through lenses, over a sweep, on local processes or Dask.

    One EXR + PNG per item and the manifest ``batch.json`` go into `output_dir`; a failed item is
    recorded and the others go on; a batch run again skips what a former run finished
    ([batch work](../details/batch.md)). A script that calls it needs the main guard.

    Parameters
    ----------
    inputs : iterable of str or PathLike
        Images and Mitsuba scene XML files: files, folders, glob patterns.
    output_dir : str or PathLike
        Where the outputs go.
    lens : str or sequence of str
        A shipped lens's name or a lens file, or a list of them (swept).
    spec : RenderSpec, optional
        The renders' settings (`render.spec.RenderSpec`, as `render.image.render_image` takes them; its
        `seed` the batch's base seed); default: its defaults.
    workers : int, optional
        Local processes; default: the cores.
    dask : str, optional
        A Dask scheduler's address, or "local" (a LocalCluster for this batch).
    force : bool, default False
        Run even when the estimated memory exceeds what is free.
    progress : bool, default True
        Show progress on stderr.
    camera : isp.camera.Camera, optional
        Each rendered frame through a sensor and image processor, its RAW and developed frame beside it,
        seeded by the camera's seed and the item's name.
    calibration_model : str, optional
        The camera model (`optics.calibration.MODELS`) whose fit to the lens each output's camera block
        records, fitted once per lens and sensor before any item (`image_cameras`; the manifest's
        ``cameras`` holds them); default: none.
    **settings
        Fields of `RenderSpec` to change; ``focus_distance`` (scenes only), ``sensor`` (images only),
        ``pitch_um`` and ``spp`` take one value or a list each (swept).

    Returns
    -------
    BatchResult
        Its items (`jobs`, each with its status and sweep point) and the manifest's path.

    Raises
    ------
    SolasError
        For bad inputs, settings, workers or scheduler, or a batch that would not fit in memory.

    Examples
    --------
    >>> import numpy as np
    >>> from solas_mi.batch import render_batch
    >>> from solas_mi.imageio import write_png
    >>> write_png("frame.png", np.full((48, 64, 3), 0.5, np.float32))
    >>> done = render_batch(["frame.png"], "rendered", lens="solas-doublet", sensor=(24, 32), spp=[1, 2],
    ...                     workers=1, progress=False)
    >>> [(job.status, job.params["spp"]) for job in done.jobs]
    [('done', 1), ('done', 2)]
    """
    from ..budget import check_memory
    from .runner import run_batch

    start = time.perf_counter()
    check_dask(dask)
    n = check_workers(workers, dask)
    p = plan_render(inputs, output_dir, lens=lens, spec=spec, camera=camera, **settings)
    check_memory(
        f"batch of {len(p.todo)} renders on {n} workers", estimate(p, n if dask is None else 1)["peak_bytes"], force
    )
    chosen = batch_variant(p)
    cameras = image_cameras(p, calibration_model)
    # each local worker (and each Dask worker of a LocalCluster) gets its share of the cores, so that
    # the local and the Dask runs render with the same thread count (identical sums)
    threads = worker_threads(n, dask)
    p.manifest.header.update(
        {
            "variant": chosen,
            "settings": {k: v for k, v in p.spec.as_dict().items() if k not in SWEEP},
            "threads_per_worker": threads,
            **({"camera": camera.describe()} if camera is not None else {}),
            "calibration_model": calibration_model,
            "cameras": cameras,
            "runner": {"dask": dask} if dask is not None else {"workers": n},
        }
    )
    settings = {
        "camera": camera,
        "batch": {"id": p.key, "manifest": str(p.manifest.path)},
        "calibration_model": calibration_model,
        "cameras": cameras,
    }
    run_batch(p.manifest, p.todo, None, None, settings, n, dask, "render" if progress else None)
    return BatchResult(p.jobs, p.manifest.path, None, "none", time.perf_counter() - start)
