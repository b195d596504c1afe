"""The one list of lens analyses, a `solas_mi.registry.Registry`: name → its function (loaded from its
module when it runs), the options it takes (keywords of `options.OPTIONS`, `extra["keywords"]`), a one-line
summary, its reference. The `solas-mi lens <name>` commands, their help, `lens report` and the docs'
list are derived from it; a new analysis is one module (a function returning a `base.Result`) and one
`register` call here. Light: imports no analysis until one runs.
"""

from __future__ import annotations

from collections.abc import Callable
from importlib import import_module

from ..registry import Registry

_CHOSEN = ("fields_deg", "wavelengths_nm", "weights")  # an analysis at chosen fields, polychromatic
_MTF = ("pupil_samples", "pixel_pitch_um", "fill_factor")  # how an MTF is computed and seen
_AGAINST_FIELD = ("field_samples", "wavelengths_nm")

ANALYSES = Registry("lens analysis", shown=("keywords",))
"""The lens analyses by name (a `solas_mi.registry.Registry`): each entry's function `f(lens, **options)`
returning a `base.Result`, the option keywords it takes (`extra["keywords"]`, of `options.OPTIONS`), a
summary and a reference; the [table of analyses](registries.md)."""


def _loaded(module: str, function: str) -> Callable:
    """`function` of `module` (relative to this package), imported when first called: `f(lens, **options)`."""

    def run(lens, **options):
        return getattr(import_module(module, __package__), function)(lens, **options)

    run.__name__ = run.__qualname__ = function
    return run


def _register(name: str, module: str, function: str, keywords: tuple[str, ...], summary: str, reference: str) -> None:
    """Register `function` of `module` as `name`, taking the options `keywords` (of `options.OPTIONS`)."""
    ANALYSES.register(name, _loaded(module, function), summary=summary, reference=reference, keywords=keywords)


_register(
    "mtf",
    ".mtf",
    "mtf",
    (*_CHOSEN, "max_frequency_cy_mm", "rays", *_MTF),
    "MTF against spatial frequency, tangential and sagittal, diffraction (pupil autocorrelation) and "
    "geometric, at chosen fields",
    "J. W. Goodman, Introduction to Fourier Optics, 3rd ed. (2005), 6.3: the OTF as the pupil's autocorrelation",
)
_register(
    "mtf-field",
    ".mtf_field",
    "mtf_field",
    ("frequencies_cy_mm", "field_samples", "wavelengths_nm", "weights", *_MTF),
    "diffraction MTF against field at chosen frequencies, tangential and sagittal",
    "Goodman (2005), 6.3",
)
_register(
    "mtf50-field",
    ".mtf_field",
    "mtf50_field",
    ("field_samples", "wavelengths_nm", "weights", *_MTF),
    "MTF50 (the frequency where the diffraction MTF falls to 1/2) against field, tangential and sagittal",
    "ISO 12233:2017 (MTF50)",
)
_register(
    "through-focus",
    ".through_focus",
    "through_focus",
    ("frequency_cy_mm", "fields_deg", "wavelengths_nm", "weights", "focus_range_um", "focus_steps", *_MTF),
    "diffraction MTF at one frequency against the image plane's position, tangential and sagittal",
    "Goodman (2005), 6.4 (defocus)",
)
_register(
    "field-curvature",
    ".field_curvature",
    "field_curvature",
    _AGAINST_FIELD,
    "tangential and sagittal focus against field (field curvature and astigmatism), from pairs of "
    "rays beside the chief ray",
    "W. J. Smith, Modern Optical Engineering, 4th ed. (2008), 3.5 (astigmatism and field curvature)",
)
_register(
    "distortion",
    ".distortion",
    "distortion",
    ("field_samples", "wavelength_nm"),
    "distortion against field: against f tan(theta), f theta and the closest projection",
    "Smith (2008), 3.5 (distortion)",
)
_register(
    "lateral-colour",
    ".colour",
    "lateral_colour",
    _AGAINST_FIELD,
    "lateral colour against field: each wavelength's chief-ray image height minus the primary's",
    "Smith (2008), 3.5 (lateral colour)",
)
_register(
    "relative-illumination",
    ".colour",
    "relative_illumination",
    _AGAINST_FIELD,
    "relative illumination against field: image irradiance over the on-axis irradiance",
    "M. Reiss, JOSA 35 (1945) 283 and 38 (1948) 980; solas_mi.optics.illumination",
)
_register(
    "ray-fan",
    ".fans",
    "ray_fan",
    ("fields_deg", "wavelengths_nm", "fan_samples"),
    "transverse ray aberration against pupil coordinate, tangential and sagittal fans",
    "Smith (2008), 11.2 (ray intercept curves)",
)
_register(
    "opd-fan",
    ".fans",
    "opd_fan",
    ("fields_deg", "wavelengths_nm", "fan_samples"),
    "optical path difference against pupil coordinate, tangential and sagittal fans, in waves",
    "H. H. Hopkins, Wave Theory of Aberrations (1950)",
)
_register(
    "wavefront",
    ".wavefront",
    "wavefront",
    ("fields_deg", "wavelength_nm", "pupil_samples", "zernike", "zernike_terms"),
    "the wavefront (OPD) map over the pupil and its Zernike terms, in waves",
    "V. N. Mahajan, Optical Imaging and Aberrations, Part II (2011); R. J. Noll, JOSA 66 (1976) 207",
)
_register(
    "spot-diagram",
    ".spots",
    "spot_diagram",
    ("fields_deg", "wavelengths_nm", "rings"),
    "spot diagrams over fields and wavelengths, with RMS radii and the Airy disc",
    "Smith (2008), 11.3",
)
_register(
    "encircled-energy",
    ".energy",
    "encircled_energy",
    ("fields_deg", "wavelength_nm", "pupil_samples", "energy_reference"),
    "encircled and ensquared energy against radius (half width) of the diffraction PSF",
    "Goodman (2005); ISO 11146 (centroid)",
)
