"""`solas-mi batch degrade` (many images degraded by one PSF grid) and `solas-mi batch render` (images
and scene files rendered through a lens, swept over lenses, focus, sensor, pitch and spp), on local
processes or Dask.

Exit status 0 when every item is done (or was already), 1 when any item failed (after finishing the
others; the manifest `batch.json` says which and why), 2 for a mistake in the arguments.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ..caches import ENV
from ..errors import SolasError
from ..isp.commands import add_camera_options, camera_from_args

# the grid options whose defaults differ from `psf-grid`'s: the grid (rows, columns), the accuracy tables'
# interp 32×24 on a 4:3 frame (README)
BATCH_GRID_DEFAULTS = {"grid": (32, 32)}


# the DegradeSpec flags of `batch degrade`'s main group (--scale-lens is the frames' camera's; the frame, camera
# and grid are built from their own flags)
DEGRADE_OPTIONS = (
    "method",
    "boundary",
    "linear",
    "output_format",
    "depth_pattern",
    "label_patterns",
    "occlusion",
    "silhouette",
    "calibration_model",
    "ghosts",
    "ghost_threshold",
)


def _degrade_spec(args: argparse.Namespace):
    """The batch's DegradeSpec from its flags: the frames' camera, the camera and, with --lens, the grid
    (the `psf-grid` options, their defaults BATCH_GRID_DEFAULTS')."""
    from ..convolution.commands import frame_from_args
    from ..convolution.spec import DegradeSpec
    from ..psf.spec import GridSpec

    grid = GridSpec.from_args(args, defaults=BATCH_GRID_DEFAULTS) if args.lens or args.lens_population else None
    return DegradeSpec.from_args(
        args, frame=frame_from_args(args), camera=camera_from_args(args, args.seed), grid_spec=grid
    )


def _lens(args: argparse.Namespace):
    """--lens as a Lens where --temperature-c or --pressure-kpa moves it (`optics.commands.load_lens`), else as
    given (a name or file, which the batch loads)."""
    if args.lens_population is not None and (args.temperature_c, args.pressure_kpa, args.mount) != (None,) * 3:
        raise SolasError(
            "--temperature-c, --pressure-kpa and --mount are for --lens; a lens population's frames "
            "take their temperatures from --frame-temperatures-c"
        )
    if args.lens is None or (args.temperature_c is None and args.pressure_kpa is None):
        return args.lens
    from ..optics.commands import load_lens

    return load_lens(args)


def _dry_run(args: argparse.Namespace) -> int:
    from ..budget import size_text
    from .degrade import check_workers, estimate, plan_batch

    workers = check_workers(_workers(args.workers), args.dask)
    p = plan_batch(args.inputs, args.output, _degrade_spec(args), **_sources(args))
    need = estimate(p, workers if args.dask is None else 1)
    where = f"Dask at {args.dask}" if args.dask else f"{workers} local worker process(es)"
    skipped = len(p.jobs) - len(p.todo)
    scale = p.lens_scale
    scaled = f"; lens scaled x{scale['factor']:.4g} to EFL {scale['efl_mm'][1]:.4g} mm" if scale else ""
    grid_s, grid = _grid_plan(p)
    print(f"1. PSF grid: {p.grid_path} ({grid}{scaled})")
    print(
        f"2. degrade {len(p.todo)} of {len(p.jobs)} images ({skipped} already finished, skipped) "
        f"with {p.spec.method}, boundary {p.spec.boundary}, on {where}"
    )
    files = "16-bit PNG + JSON" if p.spec.output_format == "png16" else "EXR + PNG"
    labels = "".join(
        f" + warped labels {Path(f).suffix[1:].upper()}" for f in (p.jobs[0].label_outputs if p.jobs else [])
    )
    print(f"3. write {files}{labels}{_camera_files(p.jobs)} per image and {p.manifest.path}")
    print(
        f"estimate: about {grid_s + need['seconds']:.3g} s ({grid_s:.3g} s for the grid, {need['seconds']:.3g} s of "
        f"degrading), peak memory about {size_text(need['peak_bytes'])} (grid {size_text(need['grid_bytes'])} per "
        "worker)"
    )
    return 0


def _sources(args: argparse.Namespace) -> dict:
    """`batch degrade`'s grid: a file, a lens or a lens population, and the grid cache (keywords of `plan_batch`
    and `degrade_batch`)."""
    return {"psf_grid": args.psf_grid, "lens": _lens(args), "cache": args.cache, **_population(args, args.seed)}


def _population(args: argparse.Namespace, seed: int) -> dict:
    """The lens population of a batch (`population.Population`: the folder, `seed`, the frames' temperatures)
    as `degrade_batch`'s keyword; {} without one (and SolasError for temperatures without one)."""
    if args.lens_population is None:
        if args.frame_temperatures_c:
            raise SolasError(
                "--frame-temperatures-c is for --lens-population; give one lens at its temperature with --lens"
            )
        return {}
    from .population import Population

    return {"lens_population": Population(args.lens_population, seed, tuple(args.frame_temperatures_c or ()))}


def _grid_plan(p) -> tuple[float, str]:
    """Seconds the batch's grid will take and what is done with it: reused (a file given, or a cache
    entry of this lens and grid), or computed, its time measured on a few of its PSFs (`psf.cost`); a
    population's grids: one per lens instance its items use, each as long as the first lens's."""
    if p.grid_source == "population":
        from ..psf.cost import grid_cost

        used = len({p.jobs[i].params["lens"]["hash"] for i in p.todo})
        return used * grid_cost(p.lens, p.grid_spec).seconds, f"{used} lens instances of {p.grid_path}, each cached"
    if p.grid_source != "to compute":
        return 0.0, {"given": "given", "cache hit": "in the cache: reused, nothing to compute"}[p.grid_source]
    from ..psf.cost import grid_cost

    cost = grid_cost(p.lens, p.grid_spec)
    return cost.seconds, f"not in the cache: computed once, {cost.text()}; then cached"


def run_batch_degrade(args: argparse.Namespace) -> int:
    if args.dry_run:
        return _dry_run(args)
    from .degrade import degrade_batch

    result = degrade_batch(
        args.inputs,
        args.output,
        _degrade_spec(args),
        **_sources(args),
        workers=_workers(args.workers),
        dask=args.dask,
        force=args.force,
        progress=not args.quiet,
    )
    return _report("degrade", result, f" (grid: {result.grid_source})")


def _camera_files(jobs) -> str:
    """What the camera adds per item (its RAW, developed frame), for the dry run's list."""
    extras = jobs[0].extras if jobs else []
    return "".join([" + RAW EXR", " + developed PNG"][: len(extras)])


WARNINGS_SHOWN = 5  # items whose warnings are printed; the manifest holds every item's


def _report(command: str, result, extra: str = "") -> int:
    for job in result.failed:
        print(f"solas-mi batch {command}: failed: {job.input} → {job.output}: {job.error}", file=sys.stderr)
    warned = [job for job in result.jobs if job.warnings and job.status == "done"]
    for job in warned[:WARNINGS_SHOWN]:
        for text in job.warnings:
            print(f"solas-mi batch {command}: warning: {text}", file=sys.stderr)
    if len(warned) > WARNINGS_SHOWN:
        print(
            f"solas-mi batch {command}: warning: {len(warned) - WARNINGS_SHOWN} more items warn likewise (each "
            f"item's warnings are in {result.manifest})",
            file=sys.stderr,
        )
    print(
        f"{result.count('done')} done, {result.count('skipped')} skipped, {len(result.failed)} failed "
        f"in {result.seconds:.1f} s{extra}; manifest {result.manifest}"
    )
    return 1 if result.failed else 0


# the render settings `batch render` takes: every one of `render-image`'s, and a scene file's focus distance and labels
RENDER_SETTINGS = (
    "sensor",
    "pitch_um",
    "fov_deg",
    "response",
    "boundary",
    "fresnel",
    "rings",
    "mapping",
    "spp",
    "variant",
    "seed",
    "focus_distance",
    "labels",
)


def _render_spec(args: argparse.Namespace):
    """The batch's RenderSpec and its sweep (`batch.render.SWEEP`'s fields given lists) from the flags: the
    spec holds each swept field's first value."""
    from ..render.spec import RenderSpec
    from .render import SWEEP

    values = RenderSpec.given(args, RENDER_SETTINGS, sweep=SWEEP[1:])
    sweep = {name: values[name] for name in SWEEP[1:] if name in values}
    return RenderSpec(**{**values, **{name: swept[0] for name, swept in sweep.items()}}), sweep


def run_batch_render(args: argparse.Namespace) -> int:
    from .runner import check_dask

    workers = _workers(args.workers)
    check_dask(args.dask)
    spec, sweep = _render_spec(args)
    camera = camera_from_args(args, spec.seed)
    if args.dry_run:
        from ..budget import size_text
        from .degrade import check_workers
        from .render import batch_variant, estimate, plan_render

        n = check_workers(workers, args.dask)
        p = plan_render(args.inputs, args.output, lens=_render_lens(args, spec.seed), spec=spec, camera=camera, **sweep)
        need = estimate(p, n if args.dask is None else 1)
        where = f"Dask at {args.dask}" if args.dask else f"{n} local worker process(es)"
        swept = ", ".join(f"{k} ({len(v)} values)" for k, v in p.manifest.header["sweep"].items()) or "nothing"
        print("1. no PSF grid (a direct render through the lens)")
        print(
            f"2. render {len(p.todo)} of {len(p.jobs)} items ({len(p.jobs) - len(p.todo)} already finished, "
            f"skipped; swept: {swept}) with Mitsuba {batch_variant(p)}, on {where}"
        )
        print(f"3. write EXR + PNG{_camera_files(p.jobs)} per item and {p.manifest.path}")
        print(
            f"estimate: about {need['seconds']:.1f} s ({need['samples']:.3g} samples), peak memory about "
            f"{size_text(need['peak_bytes'])}"
        )
        return 0
    from .render import render_batch

    result = render_batch(
        args.inputs,
        args.output,
        lens=_render_lens(args, spec.seed),
        spec=spec,
        **sweep,
        workers=workers,
        dask=args.dask,
        force=args.force,
        progress=not args.quiet,
        camera=camera,
        calibration_model=args.calibration_model,
    )
    return _report("render", result)


def _render_lens(args: argparse.Namespace, seed: int):
    """`batch render`'s lenses: --lens (one or a sweep), or the population of --lens-population (`_population`)."""
    return _population(args, seed).get("lens_population", args.lens)


def _workers(text: str | None) -> int | None:
    if text is None:
        return None
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise SolasError(f"--workers {text!r} must be a whole number >= 1")
    return value


def _add_runner_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("-o", "--output", required=True, metavar="OUT_DIR", help="output folder")
    p.add_argument(
        "--workers",
        help="local worker processes (default: the machine's cores); with --dask local, the LocalCluster's workers",
    )
    p.add_argument("--dask", metavar="ADDRESS", help="Dask scheduler (tcp://HOST:PORT), or local for a LocalCluster")
    p.add_argument(
        "--dry-run", action="store_true", help="print the stages, what is reused and an estimate; do nothing"
    )
    p.add_argument("--force", action="store_true", help="run even when the estimated memory exceeds what is free")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def _add_population_options(group, p: argparse.ArgumentParser) -> None:
    """--lens-population (in `group`, beside the batch's other lens sources) and --frame-temperatures-c."""
    group.add_argument(
        "--lens-population",
        metavar="DIR",
        help="a folder of lens files (a `solas-mi tolerance` output): each frame through one of them, picked by "
        "--seed and its name as its noise is; the manifest names each frame's lens",
    )
    p.add_argument(
        "--frame-temperatures-c",
        type=float,
        nargs="+",
        metavar="C",
        help="with --lens-population: each frame's lens at one of these temperatures (°C), picked by --seed and "
        "its name",
    )


def _add_degrade(sub: Any) -> None:
    """Add `batch degrade`."""
    from ..convolution.commands import add_frame_options
    from ..convolution.spec import DegradeSpec
    from ..optics.commands import add_environment_options
    from ..optics.formats import lens_help
    from ..psf.spec import GridSpec

    p = sub.add_parser(
        "degrade",
        help="degrade images (files, folders, glob patterns) with one PSF grid",
        description="Degrade every input image with one PSF grid — a given file, or computed once from --lens "
        "and cached — writing OUT_DIR/<name>.exr + .png and OUT_DIR/batch.json. Finished items are "
        "skipped on a re-run; a failed item is reported and the others go on (exit status 1).",
    )
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="image files, folders of images, or glob patterns")
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--psf-grid", metavar="GRID.exr", help="PSF grid written by `solas-mi psf-grid`")
    source.add_argument("--lens", help=f"compute the grid from this lens: {lens_help()}")
    _add_population_options(source, p)
    add_environment_options(p)
    DegradeSpec.add_flags(p, DEGRADE_OPTIONS)
    frames = p.add_argument_group("the frames' camera (as degrade's; every input taken by it)")
    add_frame_options(frames)
    DegradeSpec.add_flags(frames, ("scale_lens",))
    add_camera_options(p, seed=True)
    p.add_argument(
        "--cache", metavar="DIR", help=f"PSF-grid cache (default: psf-grids in ${ENV}, else in the user's cache folder)"
    )
    _add_runner_options(p)
    GridSpec.add_flags(
        p.add_argument_group(
            "grid options (with --lens; those of `solas-mi psf-grid`, the grid "
            "itself the accuracy tables' interp grid by default)"
        ),
        defaults=BATCH_GRID_DEFAULTS,
    )
    p.set_defaults(run=run_batch_degrade)


def register(subparsers: Any) -> None:
    """Add `batch` and its `degrade` and `render`."""
    from ..optics.calibration.command import add_calibration_option
    from ..optics.formats import lens_help
    from ..render.spec import RenderSpec
    from .render import SWEEP

    batch = subparsers.add_parser(
        "batch",
        help="many images at once, on local processes or a Dask cluster",
        description="Batch work, resumable, with a manifest batch.json in the output folder.",
    )
    sub = batch.add_subparsers(dest="batch_command", metavar="COMMAND", required=True)
    _add_degrade(sub)

    r = sub.add_parser(
        "render",
        help="render images and scene files through a lens, swept over lenses, focus, sensor, spp",
        description="Render every input — images (the lens's image-object scene, as `solas-mi render-image`) and "
        "Mitsuba scene XML files (the lens camera in place of the scene's camera, as `solas-mi render "
        "SCENE --lens`) — at every point of the sweep (the product of the values of --lens, "
        "--focus-distance, --sensor, --pitch-um, --spp), writing OUT_DIR/<name>[_<swept values>].exr + "
        ".png and OUT_DIR/batch.json. Finished items are skipped on a re-run; a failed item is reported "
        "and the others go on (exit status 1).",
    )
    r.add_argument("inputs", nargs="+", metavar="INPUT", help="images or scene XML files, folders of them, or globs")
    lenses = r.add_mutually_exclusive_group(required=True)
    lenses.add_argument(
        "--lens",
        action="append",
        help=f"{lens_help()}; repeat to sweep over lenses (a lens at another temperature or pressure: "
        "its file, from `solas-mi lens convert LENS --temperature-c T -o FILE.toml`)",
    )
    _add_population_options(lenses, r)
    RenderSpec.add_flags(r, RENDER_SETTINGS, sweep=SWEEP[1:])
    add_calibration_option(r)
    add_camera_options(r, seed=False, scenes=True)  # the sensor's seed is the batch's --seed
    _add_runner_options(r)
    r.set_defaults(run=run_batch_render)
