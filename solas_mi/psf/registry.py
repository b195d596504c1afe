"""The PSF methods by name: `METHODS`, a `registry.Registry` name → entry (the function that computes
it and its own sampling options), the one list every caller uses (Python, CLI, PSF grids, the
cross-validation); `method_options` routes to each method only its own options.

Every method function has the signature

    compute(lens, field_deg, wavelength_nm, pitch_um, size, *, shared_origin=False, **own_options) -> Computed

for n field/wavelength pairs (`base.Computed`: unnormalised PSFs in 1/µm², chief rays, transmitted
power, vignetting surfaces). This module imports neither NumPy nor a method's module (they load
Dr.Jit; each is imported when it computes), so that a later stage can register its own method at
import time without loading anything: the render stage adds its own (`solas_mi.render`), which
keeps `psf` free of any import of a later stage.
"""

from __future__ import annotations

from ..registry import Option, Registry

# largest sampling per side: 4096² = 16.8 M rays per PSF (about 1 GB of float64 working arrays);
# Dr.Jit refuses arrays beyond 2^32 entries long before memory would
MAX_SAMPLING = 4096

DEFAULT_PUPIL_SAMPLES = 128
DEFAULT_GEOMETRIC_RAYS = 512
PUPIL_SAMPLES = Option(
    "pupil_samples",
    int,
    DEFAULT_PUPIL_SAMPLES,
    "N×N pupil grid",
    minimum=8,
    maximum=MAX_SAMPLING,
    label="pupil samples",
)
RAYS = Option("rays", int, DEFAULT_GEOMETRIC_RAYS, "rays × rays per PSF", minimum=2, maximum=MAX_SAMPLING)

DEFAULT_METHOD = "fraunhofer"
METHODS = Registry("PSF method", default=DEFAULT_METHOD)
"""The PSF methods by name (a `solas_mi.registry.Registry`): each entry's function, its own options, a summary
and a reference; the [table of methods](registries.md)."""
check_method = METHODS.get
method_options = METHODS.options  # (name, {keyword: value}) -> the method's own options, checked


@METHODS.register(
    "fraunhofer",
    options=(PUPIL_SAMPLES,),
    summary="|matrix DFT of the pupil function|^2 (diffraction and aberrations)",
    reference="J. W. Goodman, Introduction to Fourier Optics, 3rd ed., 2005; Soummer et al., "
    "Optics Express 15(24), 2007",
)
def _fraunhofer(*args, **kwargs):
    from .fraunhofer import compute

    return compute(*args, most=MAX_SAMPLING, **kwargs)


@METHODS.register("geometric", options=(RAYS,), summary="real rays on a regular entrance grid, binned per pixel")
def _geometric(*args, **kwargs):
    from .geometric import compute

    return compute(*args, **kwargs)
