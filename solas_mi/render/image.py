"""An input image through the lens geometry: the lens's scene (`scene`) written to a temporary
directory with the image as its object, loaded (`mitsuba`) and rendered (`loop`)."""
from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from ..imageio import image_channels, read_image, write_exr
from ..optics.camera import camera_for
from . import response as responses
from .loop import Render, render
from .mitsuba import load_scene
from .scene import DEFAULT_RINGS, write_scene


def render_image(lens, image: str | np.ndarray, sensor: tuple[int, int] = (960, 1280), pitch_um: float | None = None,
                 spp: int = 64, response: str = "srgb", fov_deg: float | None = None, boundary: str = "edge",
                 fresnel: str = "transmit", rings: int | None = None, variant: str | None = None, seed: int = 0,
                 progress=None) -> Render:
    """Render an input image (a path, or a linear H×W[×3] array) through `lens` onto a sensor of
    (rows, columns) pixels of `pitch_um` µm, `spp` samples per pixel. The image's width spans
    ±`fov_deg` degrees (default: ±lens.field_deg) and the sensor's width the same field unless
    `pitch_um` is given (`solas_mi.optics.camera`). `response`, `boundary` and `fresnel` are the
    plugins' parameters; `rings` per cap mesh (default `scene.DEFAULT_RINGS`)."""
    camera = camera_for(lens, sensor, fov_deg, pitch_um)
    # the user's mistakes, named here rather than inside the scene's plugins
    responses.check_lens(responses.parse(response, lens.wavelengths_nm), lens)
    if not isinstance(image, np.ndarray):
        read_image(image)
    with tempfile.TemporaryDirectory(prefix="solas-scene-") as tmp:
        if isinstance(image, np.ndarray):
            path = str(Path(tmp) / "object.exr")
            write_exr(path, image_channels(np.asarray(image, dtype=np.float32)))
            image = path
        xml = write_scene(lens, tmp, str(Path(image).resolve()), camera, rings or DEFAULT_RINGS, spp, response,
                          boundary, fresnel)
        scene = load_scene(xml, variant)
        result = render(scene, spp, seed=seed, progress=progress)
    result.meta.update(camera.meta())
    result.meta.update({"lens": lens.name, "lens_hash": lens.hash, "boundary": boundary, "fresnel": fresnel,
                        "cap_rings": rings or DEFAULT_RINGS})
    return result
