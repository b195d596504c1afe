"""Any Mitsuba scene rendered with its own integrator (stock `path`, `volpath`, `aov`, …), in passes of
bounded memory: the JIT variants trace a pass as one wavefront, so the samples of a large image are
split over several passes of independent seeds and averaged (each pass is an unbiased estimate of the
film's value, so the spp-weighted mean is too).

Pixel values are what the scene's film develops (hdrfilm: linear RGB; specfilm: one channel per
sensitivity; aov: the extra channels after the colour ones), written with the film's channel names.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..errors import plugin_error
from .loop import Render
from .mitsuba import check_run, pass_seed

# bounds the memory of one wavefront, and its time: a signal is answered between passes (a pass is at least one
# sample per pixel: `docs/details/render.md`, "Interruptions")
SAMPLES_PER_PASS = 1 << 20


def render_scene(scene, spp: int, seed: int = 0, progress=None, labels=()) -> Render:
    """Render `scene` (loaded by `mitsuba.load_scene`) with its own integrator and `spp` samples per pixel;
    `labels` (names of `render.labels.LABELS`, or them comma-separated, through the scene's lens_camera) become
    the result's `layers`, their metadata its meta's "labels"."""
    import mitsuba as mi

    check_run(spp, seed)
    layers, label_meta = {}, None  # traced first: a scene without a lens camera is refused before its render
    if labels:
        from .labels import render_labels

        layers, label_meta = render_labels(scene, labels)
    sensor = scene.sensors()[0]
    film = sensor.film()
    width, height = (int(v) for v in film.crop_size())
    per_pass = spp if not mi.variant().startswith(("llvm", "cuda")) else max(1, min(spp, SAMPLES_PER_PASS // (width * height)))
    passes = math.ceil(spp / per_pass)
    total, names, done = None, None, 0
    start = time.perf_counter()
    for k in range(passes):
        n = min(per_pass, spp - done)
        try:
            mi.render(scene, seed=pass_seed(seed, k), spp=n)
        except RuntimeError as exc:  # a plugin's refusal (e.g. an integrator that cannot see through a lens)
            raise plugin_error(exc, "render") from None
        bitmap = film.bitmap()
        names = [bitmap.struct_()[i].name for i in range(bitmap.channel_count())]
        image = np.array(bitmap, dtype=np.float64).reshape(height, width, len(names))
        total = image * n if total is None else total + image * n
        done += n
        if progress is not None:
            progress(done, spp)
    seconds = time.perf_counter() - start
    image = (total / spp).astype(np.float32)
    integrator = str(scene.integrator()).split("[", 1)[0]
    result = Render(image, tuple(names), spp, seconds, width * height * spp / seconds,
                    {"variant": mi.variant(), "integrator": integrator, "sensor": str(sensor).split("[", 1)[0],
                     "passes": passes, "seconds": seconds})
    if labels:
        result.layers, result.meta["labels"] = layers, label_meta
    return result
