"""The PSF methods by name: `METHODS`, a mapping name → `PSFMethod` (the function that computes it
and its own sampling options), the one list every caller uses (Python, CLI, PSF grids, the
cross-validation). Modelled on colour-science's `*_METHODS` mappings with one dispatcher
(`colour.colorimetry.tristimulus_values`): `method_options` routes to each method only its own options.

Every method function has the signature

    compute(lens, field_deg, wavelength_nm, pitch_um, size, *, shared_origin=False, **own_options) -> Computed

for n field/wavelength pairs (`base.Computed`: unnormalised PSFs in 1/µm², chief rays, transmitted
power, vignetting surfaces). This module imports neither NumPy nor a method's module (they load
Dr.Jit; each is imported when it computes), so that a later stage can register its own method at
import time without loading anything: the render stage adds "render" (`solas_mi.render`), which
keeps `psf` free of any import of a later stage.
"""
from __future__ import annotations

from dataclasses import dataclass
from numbers import Integral
from typing import Callable

from ..errors import SolasError

# largest sampling per side: 4096² = 16.8 M rays per PSF (about 1 GB of float64 working arrays);
# Dr.Jit refuses arrays beyond 2^32 entries long before memory would
MAX_SAMPLING = 4096


@dataclass(frozen=True)
class Sampling:
    """A method's own sampling option: its keyword, default, smallest value and meaning."""

    name: str
    default: int
    minimum: int
    meaning: str  # "pupil samples" or "rays (rays × rays per PSF)"

    def check(self, value) -> int:
        if not isinstance(value, Integral) or isinstance(value, bool) or not self.minimum <= value <= MAX_SAMPLING:
            what, _, per = self.meaning.partition(" (")
            raise SolasError(f"{what} {value!r} must be an integer from {self.minimum} to {MAX_SAMPLING}"
                             + (f" ({per}" if per else ""))
        return int(value)


DEFAULT_PUPIL_SAMPLES = 128
DEFAULT_GEOMETRIC_RAYS = 512
PUPIL_SAMPLES = Sampling("pupil_samples", DEFAULT_PUPIL_SAMPLES, 8, "pupil samples (N×N pupil grid)")
RAYS = Sampling("rays", DEFAULT_GEOMETRIC_RAYS, 2, "rays (rays × rays per PSF)")
SAMPLINGS = (PUPIL_SAMPLES, RAYS)  # every method's option, by keyword


@dataclass(frozen=True)
class PSFMethod:
    """A PSF method: the function that computes it, its own options, a one-line summary, its reference."""

    name: str
    compute: Callable
    options: tuple[Sampling, ...]
    summary: str
    reference: str = ""


METHODS: dict[str, PSFMethod] = {}
DEFAULT_METHOD = "fraunhofer"


def register_method(method: PSFMethod) -> None:
    """Add a method (a later stage registers its own; a name is registered once)."""
    if METHODS.get(method.name, method) != method:
        raise SolasError(f"PSF method {method.name!r} is registered already")
    METHODS[method.name] = method


def check_method(name) -> PSFMethod:
    if not isinstance(name, str) or name not in METHODS:
        raise SolasError(f"PSF method {name!r} must be one of {', '.join(METHODS)}")
    return METHODS[name]


def method_options(name: str, options: dict) -> dict[str, int]:
    """The options of method `name` among `options` (keyword → value; None or absent: the default),
    checked; the options of other methods are left out, a name no method knows is an error."""
    known = {s.name for s in SAMPLINGS}
    unknown = sorted(set(options) - known)
    if unknown:
        raise SolasError(f"PSF options {', '.join(unknown)} are unknown; allowed: {', '.join(sorted(known))}")
    own = check_method(name).options
    return {s.name: s.check(s.default if options.get(s.name) is None else options[s.name]) for s in own}


def _fraunhofer(*args, **kwargs):
    from .fraunhofer import compute

    return compute(*args, most=MAX_SAMPLING, **kwargs)


def _geometric(*args, **kwargs):
    from .geometric import compute

    return compute(*args, **kwargs)


register_method(PSFMethod(
    "fraunhofer", _fraunhofer, (PUPIL_SAMPLES,), "|matrix DFT of the pupil function|^2 (diffraction and aberrations)",
    "J. W. Goodman, Introduction to Fourier Optics, 3rd ed., 2005; Soummer et al., Optics Express 15(24), 2007"))
register_method(PSFMethod("geometric", _geometric, (RAYS,), "real rays on a regular entrance grid, binned per pixel"))
