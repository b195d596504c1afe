"""Flare in a lens-camera render (`solas-mi render SCENE --lens LENS --ghosts`): the direct image and the stray
light of the lens's ghosts, rendered apart and added, with the `flare` label layers.

Two renders of the scene at the same spp: the direct image (the lens camera without ghosts, its surfaces
weighed by their coatings or Fresnel's transmittance), then the stray light alone (the camera's `ghosts`
"only": every two-reflection path, `plugins/ghost_sampling.py`), each at its own seeds. The frame is their
sum, an unbiased estimate of the light through every path, in which the direct image is as converged as
without ghosts and the ghosts get every sample of the second render, and the iris's starburst spread from
the direct image (`starburst`: each pixel gives its diffraction wings' share to its neighbours).

Layers (EXR `layer.channel` names, float32, beside the image's channels and any labels): `FLARE_LAYERS`,
`flare.irradiance`, the stray light's irradiance per pixel (the ghosts' and the iris's starburst, the
diffraction of the stop's shape convolved onto the direct image: `starburst`) (the mean of the image's channels, in the
image's units), and `flare.ratio`, its ratio to the direct image's (the same mean): 0 where no stray light
arrives, `MAX_RATIO` where stray light meets a pixel that the direct image leaves dark; never NaN. The
metadata's `flare` names them and says how they were made.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import SolasError
from ..labelkinds import FLARE_LAYERS, MAX_RATIO, flare_layers

STRAY_SEED = 0x9E3779B9  # the stray-light render's seed: the frame's XOR this (its samples apart from the direct's)


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
    stray_paths = own if own is not None and own.mode == "only" else sensor.ghost_sampler("only")

    def told(offset):
        return None if progress is None else lambda done, total: progress(offset + done, 2 * total)

    try:
        sensor.ghosts = None
        direct = render_scene(scene, spp, seed, told(0), labels)
        sensor.ghosts = stray_paths
        stray = render_scene(scene, spp, seed ^ STRAY_SEED, told(spp))
    finally:
        sensor.ghosts = own
    kept, light, starburst = with_starburst(sensor, direct.image, stray.image)
    direct.layers.update(flare_layers(kept, light))
    direct.image = (kept + light).astype(np.float32)
    direct.seconds += stray.seconds
    direct.samples_per_second /= 2.0
    direct.meta["flare"] = {
        "layers": list(FLARE_LAYERS),
        "ghosts": "every two-reflection path of the lens, rendered apart from the direct image and added",
        "coatings": [k + 1 for k, s in enumerate(sensor.lens.surfaces) if s.coating is not None],
        "irradiance": "the stray light's, the mean of the image's channels",
        "ratio": f"flare.irradiance over the direct image's; 0 without stray light, {MAX_RATIO:g} where the "
        "direct image is dark",
        "starburst": starburst,
    }
    return direct


def with_starburst(sensor, direct: np.ndarray, stray: np.ndarray):
    """The direct image less the light its pixels give to the iris's diffraction wings, the stray light
    with what the wings bring (`starburst`), and what the metadata says of it; the images unchanged (None)
    for a lens without a stop or an f-number."""
    from ..psf.stray_light import working_f_number
    from .starburst import iris_kernel, spread

    lens = sensor.lens
    stops = [s for s in lens.surfaces if s.stop]
    f_number = working_f_number(lens)
    if not stops or not math.isfinite(f_number):
        return direct, stray, None
    wavelength = float(sensor.response.single_wavelength or lens.primary_wavelength)
    kernel = iris_kernel(stops[0], f_number, wavelength, float(sensor.pitch_um))
    kept, brought = spread(direct, kernel)
    centre = kernel.shape[0] // 2
    return (
        kept,
        stray + brought,
        {
            "kernel_px": kernel.shape[0],
            "wavelength_nm": wavelength,
            "f_number": f_number,
            "blades": stops[0].blades,
            "wings": float(1.0 - kernel[centre, centre]),
        },
    )
