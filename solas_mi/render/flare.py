"""Flare in a lens-camera render (`solas-mi render SCENE --lens LENS --ghosts`): the direct image and the stray
light of the lens's ghosts, rendered apart and added, with the `flare` label layers.

The direct image (the lens camera without ghosts, its surfaces weighed by their coatings or Fresnel's
transmittance), rendered at the given spp, then the stray light alone, at its own seed: traced from the
scene's light sources along every two-reflection path of the lens (`ghost_light`: converged at the direct
image's spp for a fraction of its time; the film's RGB channels), or, for a film of other channels, the
camera's own path sampling of the ghosts (`ghosts` "only", `plugins/ghost_sampling.py`) at the same spp.
The frame is their sum, an unbiased estimate of the light through every path (of the traced sources'
light, for the light-traced stray light: the metadata's `flare.sources` and `flare.not_traced`), and the
iris's starburst spread from the direct image (`starburst`: each pixel gives its diffraction wings' share
to its neighbours). An alpha channel takes no stray light.

Layers (EXR `layer.channel` names, float32, beside the image's channels and any labels): `FLARE_LAYERS`,
`flare.irradiance`, the stray light's irradiance per pixel (the ghosts' and the iris's starburst, the
diffraction of the stop's shape convolved onto the direct image: `starburst`) (the mean of the image's channels, in the
image's units), and `flare.ratio`, its ratio to the direct image's (the same mean): 0 where no stray light
arrives, `MAX_RATIO` where stray light meets a pixel that the direct image leaves dark; never NaN. The
metadata's `flare` names them and says how they were made.
"""

from __future__ import annotations

import time

import numpy as np

from ..errors import SolasError
from ..labelkinds import FLARE_LAYERS, MAX_RATIO, flare_layers

STRAY_SEED = 0x9E3779B9  # the stray light's seed: the frame's XOR this (its samples apart from the direct's)
COLOUR = ("R", "G", "B")  # the film channels the light-traced stray light develops (`ghost_light`)
PATH_SAMPLED = "path-sampled: the lens camera's ghosts 'only', rendered at the direct image's spp"


def render_with_flare(scene, spp: int, seed: int = 0, progress=None, labels=()):
    """`stock.render_scene` of `scene` (its sensor a `lens_camera`) with the stray light of its lens's
    ghosts added and the `FLARE_LAYERS` (module docstring); SolasError for another sensor."""
    from .stock import render_scene

    sensor = scene.sensors()[0]
    if not hasattr(sensor, "ghost_sampler"):
        raise SolasError(
            f"ghosts are traced through a lens camera; the scene's sensor is {type(sensor).__name__} "
            "(give --lens, or a scene with a lens_camera)"
        )
    own = sensor.ghosts  # the camera's own ghosts: "only" where --lens built it for this render
    if own is None and sensor.fresnel == "off":
        sensor.ghost_sampler("only")  # refused: lossless surfaces reflect nothing
    try:
        sensor.ghosts = None
        direct = render_scene(scene, spp, seed, progress, labels)
        start = time.perf_counter()
        rgb = tuple(direct.channels[:3]) == COLOUR
        if rgb:
            from .ghost_light import stray_light

            stray, method = stray_light(scene, sensor, spp, seed ^ STRAY_SEED)
        else:  # a film of other channels (specfilm, luminance): the camera's own path sampling develops it
            sensor.ghosts = own if own is not None and own.mode == "only" else sensor.ghost_sampler("only")
            stray, method = render_scene(scene, spp, seed ^ STRAY_SEED).image, {"method": PATH_SAMPLED}
    finally:
        sensor.ghosts = own
    seconds = time.perf_counter() - start
    colour = slice(0, 3) if rgb else slice(None)  # an alpha (or weight) channel takes no stray light
    stray = stray[..., : direct.image[..., colour].shape[-1]]
    kept, light, starburst = with_starburst(sensor, direct.image[..., colour], stray[..., colour])
    direct.layers.update(flare_layers(kept, light))
    image = direct.image.astype(np.float64)
    image[..., colour] = kept + light
    direct.image = image.astype(np.float32)
    direct.samples_per_second *= direct.seconds / (direct.seconds + seconds)
    direct.seconds += seconds
    direct.meta["flare"] = {
        "layers": list(FLARE_LAYERS),
        "ghosts": "every two-reflection path of the lens, computed apart from the direct image and added",
        **method,
        "coatings": [k + 1 for k, s in enumerate(sensor.lens.surfaces) if s.coating is not None],
        "irradiance": "the stray light's, the mean of the image's colour channels",
        "ratio": f"flare.irradiance over the direct image's; 0 without stray light, {MAX_RATIO:g} where the "
        "direct image is dark",
        "starburst": starburst,
    }
    return direct


def with_starburst(sensor, direct: np.ndarray, stray: np.ndarray):
    """The direct image less the light its pixels give to the iris's diffraction wings, the stray light
    with what the wings bring (`psf.starburst`), and what the metadata says of it; the images unchanged (None)
    for a lens without a stop or an f-number."""
    from ..psf.starburst import lens_starburst, spread

    lens = sensor.lens
    wavelength = float(sensor.response.single_wavelength or lens.primary_wavelength)
    found = lens_starburst(lens, wavelength, float(sensor.pitch_um))
    if found is None:
        return direct, stray, None
    kernel, about = found
    kept, brought = spread(direct, kernel)
    return kept, stray + brought, about
