"""One item of a batch, done where a runner placed it (`run_job`): a "degrade" item convolves its
image with the batch's PSF grid; a "render" item renders its image (the lens's image-object scene,
`render.image`) or its Mitsuba scene file (the lens camera in place of the scene's camera,
`render.user_scene` + `render.stock`) at its sweep point. No PSF grid is read for a render.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import SolasError
from ..threads import use_share
from .jobs import SCENE_SUFFIXES, Job

if TYPE_CHECKING:
    from ..psf.grid import PSFGrid

STOPPING = False  # set when this worker process is told to stop: an item failing then was interrupted


def run_job(job: Job, grid: PSFGrid | None, grid_path: str | None, settings: dict[str, Any]) -> Job:
    """Do one item and return it with its status, error and timing; never raises for the item's own
    problems (an unreadable input, a failed write): they are its `error`."""
    start = time.perf_counter()
    job.attempts += 1
    if settings.get("threads"):  # this worker's share of the cores (`runner.worker_threads`)
        use_share(settings["threads"])
    try:
        degraded = None  # a degrade item's image as its EXR holds it, for the camera (None: read from the file)
        if job.kind == "degrade":
            degraded = _degrade(job, grid, grid_path, settings)
        elif job.kind == "render":
            _render(job, settings)
        else:
            raise SolasError(f"item kind {job.kind!r} must be degrade or render")
        if settings.get("camera") is not None:
            _shoot(job, settings, degraded)
        job.stamp()
        job.status, job.error = "done", None
    except SolasError as exc:
        job.status, job.error = "failed", str(exc)
    except Exception as exc:  # one bad item never stops the batch (MemoryError included)
        job.status, job.error = "failed", f"{type(exc).__name__}: {exc}"
    except KeyboardInterrupt:
        job.status, job.error = "interrupted", "the batch was interrupted"
    if STOPPING and job.status == "failed":  # the stop surfaced inside a library (a scene load) as its error
        job.status, job.error = "interrupted", "the batch was interrupted"
    job.seconds = time.perf_counter() - start
    return job


def _degrade(job: Job, grid: PSFGrid | None, grid_path: str | None, settings: dict[str, Any]) -> tuple | None:
    """Degrade the item's image; with the batch's camera, the image as its EXR holds it (`as_written`)."""
    from ..convolution.output import degrade_file
    from ..imageio import image_size
    from ..outputs import check_target, data_and_preview

    spec = settings["spec"]  # the batch's `convolution.spec.DegradeSpec`
    cameras = settings.get("cameras", {})
    if "psf_grid" in job.params:  # a lens population's item: its own lens's grid and camera (`population`)
        from .population import item_grid

        grid_path = job.params["psf_grid"]
        grid, cameras = item_grid(grid_path), settings["population_cameras"].get(grid_path, {})
    if spec.output_format == "png16":  # a 16-bit PNG and its metadata's JSON (`plan`'s suffixes)
        output, png = (check_target(p, [job.input, grid_path]) for p in (job.output, job.png))
    else:
        output, png = data_and_preview(job.output, job.png, inputs=[job.input, grid_path])
    output.parent.mkdir(parents=True, exist_ok=True)  # a folder tree's sub-folder
    rows, cols, _ = image_size(job.input)
    # the batch's camera of the frame's size, fitted once (`convolution.camera`); none: unreadable, degrade says why
    camera = cameras.get(f"{cols}x{rows}")
    written: dict[str, Any] | None = {} if settings.get("camera") is not None else None
    meta = degrade_file(
        job.input,
        grid,
        grid_path,
        output,
        png,
        spec,
        force=settings["force"],
        depth=job.params.get("depth"),
        extra_meta={
            "batch": {**settings["batch"], "seed": job.seed, **_lens_of(job)},
            **({"camera": camera} if camera else {}),
        },
        labels=job.params.get("labels"),
        lens=settings.get("lens"),
        written=written,
    )
    return None if written is None else as_written(written["image"], meta, spec.output_format)


def as_written(image: np.ndarray, meta: dict, output_format: str) -> tuple[np.ndarray, dict] | None:
    """A degraded image and its metadata as the camera reads them back from its EXR (`sensor.commands.read_input`:
    R, G, B at the file's precision, float32 or half for exr-half, as float64), without reading the file: the same
    values; None where it is no R, G, B image (the camera reads the file, and says what it lacks)."""
    if image.ndim != 3 or image.shape[-1] != 3:
        return None
    stored = np.float16 if output_format == "exr-half" else np.float32
    return image.astype(stored, copy=False).astype(np.float64), meta


def _lens_of(job: Job) -> dict:
    """A population item's lens (file, hash, temperature), for its output's metadata; {} for others."""
    return {"lens": job.params["lens"]} if "lens" in job.params else {}


SCENE_CAMERAS: dict[tuple, dict] = {}  # this worker process's scene items' camera blocks, each fitted once


def scene_camera(scene, model: str | None) -> dict | None:
    """The camera block of a scene item (`render.commands.lens_camera`), fitted once per lens (as focused),
    film, pitch, wavelength and model in this worker process; None without a model."""
    if model is None:
        return None
    from ..render.commands import lens_camera

    sensor = scene.sensors()[0]
    key = (
        sensor.lens.hash,
        tuple(int(v) for v in sensor.film().crop_size()),
        float(sensor.pitch_um),
        sensor.response.single_wavelength,
        model,
    )
    if key not in SCENE_CAMERAS:
        SCENE_CAMERAS[key] = lens_camera(scene, model)
    return SCENE_CAMERAS[key]


def _shoot(job: Job, settings: dict[str, Any], degraded: tuple[np.ndarray, dict] | None = None) -> None:
    """The item's output through the batch's camera, read as `solas-mi camera` reads it (image irradiance,
    or radiance through the f-number it states, `sensor.commands.as_irradiance`): its RAW EXR (and
    developed frame) beside it, the frame named by its output's stem (`isp.camera`); a warning on the item
    where the RAW saturates (`sensor.commands.clipping_warning`). `degraded`: the output's image and metadata as its
    EXR holds them (`as_written`), not read back; None: read from the file."""
    from pathlib import Path

    from ..isp.camera import write_frame
    from ..sensor.commands import as_irradiance, clipping_warning, read_input

    camera = settings["camera"]
    image, own = read_input(job.output) if degraded is None else degraded
    irradiance, reading, _ = as_irradiance(image, own, job.output, camera.scale)
    raw, frame, meta = camera.shoot(irradiance, Path(job.output).stem)
    fraction, warning = clipping_warning(camera.sensor, raw, meta["exposure_ms"], Path(job.extras[0]).name)
    job.warnings = [warning] if warning else []
    meta.update(input=job.output, batch={**settings["batch"], "seed": job.seed}, saturated_fraction=fraction, **reading)
    write_frame(job.extras[0], raw, frame, meta)


def _scene_render(scene, spec, camera):
    """A scene item's render: over the batch camera's exposure windows where it has a scene timing (PWM emitters,
    camera motion: `sensor.scene_input.SceneTiming`), else still (`render.stock.render_scene`)."""
    if camera is None or camera.scene_timing is None:
        from ..render.stock import render_scene

        return render_scene(scene, spec.spp, seed=spec.seed, labels=spec.labels)
    from ..sensor.capture import as_chain

    shutter = as_chain(camera.sensor).shutter
    return camera.scene_timing.render(scene, spec.spp, shutter, camera.exposure_ms / 1e3, spec.seed)


def _render(job: Job, settings: dict[str, Any]) -> None:
    """Render the item at its settings `job.params` (its lens and `render.spec.RenderSpec`, its own
    seed included); EXR (metadata: the batch, seed, settings, Mitsuba variant) + PNG written together,
    atomically."""
    from pathlib import Path

    from ..outputs import data_and_preview, written_together
    from ..render.spec import RenderSpec
    from .population import item_lens

    p = job.params
    spec = RenderSpec.from_dict(p)
    if settings.get("threads"):
        import drjit as dr

        dr.set_thread_count(settings["threads"])  # the batch's workers share the cores (`runner.worker_threads`)
    output, png = data_and_preview(job.output, job.png, inputs=[job.input])
    lens = item_lens(p)  # its file, at its temperature where a lens population picked one
    if Path(job.input).suffix.lower() in SCENE_SUFFIXES:
        from ..render.user_scene import camera_meta, load

        scene = load(
            job.input,
            spec.variant,
            lens,
            pitch_um=spec.pitch_um,
            focus_distance=spec.focus_distance,
            response=spec.response,
        )
        block = scene_camera(scene, settings.get("calibration_model"))  # before the render: a refusal costs none
        result = _scene_render(scene, spec, settings.get("camera"))
        result.meta.update(
            scene=job.input,
            lens=lens.name,
            lens_hash=lens.hash,
            **camera_meta(scene),
            **({"camera": block} if block is not None else {}),
        )
    else:
        from ..render.image import image_sensor_key, render_image

        block = settings.get("cameras", {}).get(image_sensor_key(lens, spec)[0])  # the batch's, fitted once
        result = render_image(lens, job.input, spec, camera_block=block)
        result.meta["image"] = job.input
    result.meta["batch"] = {**settings["batch"], "seed": job.seed, "params": p}
    with written_together(output, png) as (tmp_data, tmp_png):
        result.write(tmp_data, tmp_png)
