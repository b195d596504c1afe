"""The PSF methods of `registry` for a lens as built (`optics.lens_checks.as_built`: a surface without
rotational symmetry or behind a coordinate break, or a placed sensor), which the symmetric paths do not take:
"geometric" by `psf.as_built` and "fraunhofer" by `psf.as_built_fraunhofer` (the Dr.Jit tracer in local
frames, chief rays aimed in two dimensions); the other methods are refused by name. Lengths in mm, pitches in µm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from . import as_built, as_built_fraunhofer
from .base import Computed
from .geometric import bin_hits

# method → the path that computes it for a lens as built (the PSF's metadata says which)
PATHS = {
    "geometric": "psf.as_built: real rays of the lens as built (Dr.Jit tracer in local frames), binned about the chief ray",
    "fraunhofer": "psf.as_built_fraunhofer: real rays of the lens as built (Dr.Jit tracer in local frames) to the reference "
    "sphere, matrix DFT",
}


@dataclass
class Chief:
    """The chief rays of a lens as built as the PSF's callers read them: image points (n, 2) mm on the image
    plane, in its frame, and whether an aperture blocks each (never: an unfound chief ray is refused)."""

    image_xy: np.ndarray
    vignetted: np.ndarray


def check(lens, method: str, wavelength_nm) -> None:
    """SolasError where `method` (a name of `registry.METHODS`) has no path for the lens as built `lens`, or is
    the Fraunhofer path asked for several wavelengths on one window."""
    if method not in PATHS:
        raise SolasError(
            f"lens {lens.name} is a lens as built (decentred, tilted or non-symmetric surfaces, or a placed "
            f"sensor): PSF method {method!r} does not take it; use one of {', '.join(PATHS)}"
        )
    if method == "fraunhofer" and len(set(np.ravel(wavelength_nm).tolist())) > 1:
        raise SolasError(
            f"lens {lens.name} is a lens as built: its Fraunhofer PSF takes one wavelength at a time "
            f"(not {len(set(np.ravel(wavelength_nm).tolist()))}); use method geometric for several"
        )


def compute(lens, field_deg, wavelength_nm, pitch_um: float, size: int, method: str, *, shared_origin=False, **own):
    """`methods.compute` for a lens as built: unnormalised PSFs (n, size, size) in 1/µm², each about its chief
    ray's image point or, with `shared_origin`, all about the first one's."""
    check(lens, method, wavelength_nm)
    field_deg = np.asarray(field_deg, dtype=np.float64).reshape(-1, 2)
    wavelength_nm = np.broadcast_to(np.asarray(wavelength_nm, dtype=np.float64), (len(field_deg),))
    rays = own["pupil_samples" if method == "fraunhofer" else "rays"]
    found = as_built.hits_by_wavelength(lens, field_deg, wavelength_nm, rays)
    chief = np.array([h.chief_xy for h in found])
    origins = np.repeat(chief[:1], len(chief), axis=0) if shared_origin else chief
    offsets = [((h.x - o[0]) * 1e3, (h.y - o[1]) * 1e3, h.power) for h, o in zip(found, origins)]
    data, transmission = bin_hits(offsets, pitch_um, size)  # the rays' transmitted power, for both methods
    if method == "fraunhofer":
        data = as_built_fraunhofer.fraunhofer(lens, field_deg, wavelength_nm, pitch_um, size, rays)
    chief_rays = Chief(chief, np.zeros(len(chief), dtype=bool))
    return Computed(data=data, chief=chief_rays, transmission=transmission, vignetted_by=[[] for _ in chief])


__all__ = ["PATHS", "Chief", "check", "compute"]
