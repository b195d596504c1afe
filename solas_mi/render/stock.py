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


# long: the public API's numpydoc docstring is half of it
def render_scene(scene, spp: int, seed: int = 0, progress=None, labels=()) -> Render:
    """Render a loaded Mitsuba scene with its own integrator, in passes of bounded memory.

    Parameters
    ----------
    scene : mitsuba.Scene
        The scene (`mitsuba.load_scene`).
    spp : int
        Samples per pixel.
    seed : int, default 0
        The sampler's seed (each pass's derives from it).
    progress : callable, optional
        Called as ``progress(done, total)`` with the samples per pixel done.
    labels : str or sequence of str, default ()
        Names of `render.labels.LABELS` (or them comma-separated), traced through the scene's
        ``lens_camera``.

    Returns
    -------
    Render
        The film's channels; the labels as its `layers`, their metadata its meta's "labels".

    Raises
    ------
    SolasError
        For a bad spp or seed, labels of a scene without a lens camera, or a plugin's refusal (an
        integrator that cannot see through a lens).

    Examples
    --------
    >>> from pathlib import Path
    >>> from solas_mi import Lens
    >>> from solas_mi.render import render_scene, write_scene
    >>> from solas_mi.render.mitsuba import load_scene
    >>> xml = write_scene(Lens.load("solas-doublet"), "scene", str(Path("scenes/images/rocket.png").resolve()))
    >>> render_scene(load_scene(str(xml), width=32, height=24), spp=4).image.shape
    (24, 32, 3)
    """
    import mitsuba as mi

    check_run(spp, seed)
    layers: dict[str, np.ndarray] = {}
    label_meta: dict | None = None  # traced first: a scene without a lens camera is refused before its render
    if labels:
        from .labels import render_labels

        layers, label_meta = render_labels(scene, labels)
    sensor = scene.sensors()[0]
    film = sensor.film()
    width, height = (int(v) for v in film.crop_size())
    per_pass = (
        spp
        if not str(mi.variant()).startswith(("llvm", "cuda"))
        else max(1, min(spp, SAMPLES_PER_PASS // (width * height)))
    )
    passes = math.ceil(spp / per_pass)
    total: np.ndarray | None = None
    names: list[str] = []
    done = 0
    start = time.perf_counter()
    for k in range(passes):
        n = min(per_pass, spp - done)
        try:
            mi.render(scene, seed=pass_seed(seed, k), spp=n)  # type: ignore[arg-type]  # an int seed: its stub says UInt32
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
    assert total is not None  # spp >= 1 (check_run): one pass at least
    image = (total / spp).astype(np.float32)
    integrator = str(scene.integrator()).split("[", 1)[0]
    result = Render(
        image,
        tuple(names),
        spp,
        seconds,
        width * height * spp / seconds,
        {
            "variant": mi.variant(),
            "integrator": integrator,
            "sensor": str(sensor).split("[", 1)[0],
            "passes": passes,
            "seconds": seconds,
        },
    )
    if labels:
        result.layers, result.meta["labels"] = layers, label_meta
    return result
