"""The options of the lens analyses, each defined once: its keyword (the Python functions' parameter),
its command-line flag, how a command-line value is read, its default and its help. The registry
(`registry`) names which options each analysis takes; the commands, their help and the docs list are
derived from there. Light: imports neither NumPy nor the analyses.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..errors import SolasError
from ..options import floats

# Defaults the Python functions and the commands share
PUPIL_SAMPLES = 256  # N×N pupil grid of the diffraction MTF, the wavefront and the encircled energy
MOST_PUPIL_SAMPLES = 2048  # the MTF's pupil grid where the wavefront needs more than PUPIL_SAMPLES (default)
GEOMETRIC_RAYS = 128  # rays × rays over the entrance pupil of the geometric MTF
FIELD_SAMPLES = 11  # field angles from 0 to the half field of the analyses against field
FREQUENCY_SAMPLES = 101  # frequencies from 0 to the largest of an MTF curve
FOCUS_STEPS = 21  # image-plane positions of a through-focus MTF
FAN_SAMPLES = 101  # pupil positions across a ray or OPD fan
SPOT_RINGS = 12  # rings of the hexapolar pupil pattern of a spot diagram
ZERNIKE_TERMS = 36  # Fringe Z1-Z36 is one set everywhere; Z37 differs (optiland: (6, 6), Zemax: rho^12)
ZERNIKE_KINDS = {
    "fringe": "University of Arizona order, not normalised: 1 at the rim",
    "noll": "Noll's order, each of unit RMS over the pupil",
}
ZERNIKE = "fringe"  # the default kind
ENERGY_REFERENCES = ("centroid", "chief")
FIELD_FRACTIONS = (0.0, 0.5, 0.7, 1.0)  # of the half field: the default fields of the analyses at chosen fields
FREQUENCY_FRACTIONS = (0.125, 0.25, 0.5)  # of the diffraction cut-off: the default frequencies against field
FOCUS_FRACTION = 0.25  # of the cut-off: the default frequency of a through-focus MTF
FOCUS_DEPTHS = 8.0  # the default focus range: ± this many λN² (the diffraction depth of focus, λ the primary)


def _floats(what: str) -> Callable[[str], list[float]]:
    return lambda text: floats(text, what)


def _float(what: str) -> Callable[[str], float]:
    def read(text: str) -> float:
        values = floats(text, what)
        if len(values) != 1:
            raise SolasError(f"{what} {text!r} must be one number")
        return values[0]

    return read


def _int(what: str) -> Callable[[str], int]:
    def read(text: str) -> int:
        try:
            return int(text)
        except ValueError:
            raise SolasError(f"{what} {text!r} must be a whole number") from None

    return read


@dataclass(frozen=True)
class Option:
    """One option: `keyword` of the Python functions, `flag` on the command line, `read` (text → value),
    `default` (None: what `help` says), `choices` where the value is one of a few names."""

    keyword: str
    flag: str
    read: Callable[[str], Any]
    default: Any
    help: str
    choices: tuple[str, ...] = ()

    def add_to(self, parser) -> None:
        """Add this option to an argparse parser; its value stays None unless given (then the Python
        function's default applies, which the help states)."""
        default_text = "" if self.default is None else f" (default: {self.default})"
        metavar = None if self.choices else self.flag.lstrip("-").upper().replace("-", "_")
        parser.add_argument(
            self.flag, dest=self.keyword, metavar=metavar, choices=self.choices or None, help=self.help + default_text
        )

    def value(self, args) -> Any:
        """The value of this option in parsed `args`, read; None when not given."""
        text = getattr(args, self.keyword)
        if text is None or self.choices:
            return text
        return self.read(text)


def _options(*options: Option) -> dict[str, Option]:
    return {o.keyword: o for o in options}


OPTIONS = _options(
    Option(
        "fields_deg",
        "--fields",
        _floats("--fields"),
        None,
        "y field angles in degrees, comma-separated, within the lens's half field (default: 0, 0.5, 0.7 "
        "and 1 x the half field)",
    ),
    Option(
        "field_samples",
        "--field-samples",
        _int("--field-samples"),
        FIELD_SAMPLES,
        "field angles from 0 to the half field, evenly spaced",
    ),
    Option(
        "wavelengths_nm",
        "--wavelengths-nm",
        _floats("--wavelengths-nm"),
        None,
        "nm, comma-separated (default: the lens file's)",
    ),
    Option(
        "weights",
        "--weights",
        _floats("--weights"),
        None,
        "weight of each wavelength, comma-separated (default: equal)",
    ),
    Option(
        "wavelength_nm",
        "--wavelength-nm",
        _float("--wavelength-nm"),
        None,
        "nm (default: the lens file's primary, its middle wavelength)",
    ),
    Option(
        "max_frequency_cy_mm",
        "--max-frequency",
        _float("--max-frequency"),
        None,
        "largest spatial frequency of the curves, cycles/mm (default: the diffraction cut-off 1/(lambda N) "
        "at the shortest wavelength, N the working f-number)",
    ),
    Option(
        "frequencies_cy_mm",
        "--frequencies",
        _floats("--frequencies"),
        None,
        "spatial frequencies in cycles/mm, comma-separated, up to the diffraction cut-off (default: 1/8, 1/4 "
        "and 1/2 of the cut-off at the primary wavelength, whole cycles/mm)",
    ),
    Option(
        "frequency_cy_mm",
        "--frequency",
        _float("--frequency"),
        None,
        "spatial frequency in cycles/mm, up to the diffraction cut-off (default: 1/4 of the cut-off at the "
        "primary wavelength, whole cycles/mm)",
    ),
    Option(
        "focus_range_um",
        "--focus-range-um",
        _float("--focus-range-um"),
        None,
        f"the image plane moves from -R to +R um about its place (default: {FOCUS_DEPTHS:g} lambda N^2, N the "
        "working f-number, lambda the primary wavelength)",
    ),
    Option(
        "focus_steps", "--focus-steps", _int("--focus-steps"), FOCUS_STEPS, "image-plane positions across the range"
    ),
    Option(
        "pupil_samples",
        "--pupil-samples",
        _int("--pupil-samples"),
        None,
        f"N x N samples of the pupil function (default: {PUPIL_SAMPLES}; for the MTF, more where a field's wavefront "
        f"needs them, up to {MOST_PUPIL_SAMPLES})",
    ),
    Option(
        "rays", "--rays", _int("--rays"), GEOMETRIC_RAYS, "rays x rays over the entrance pupil of the geometric MTF"
    ),
    Option(
        "pixel_pitch_um",
        "--pixel-pitch-um",
        _float("--pixel-pitch-um"),
        None,
        "multiply by the MTF of square pixels of this pitch, um (default: none, the lens alone)",
    ),
    Option(
        "fill_factor",
        "--fill-factor",
        _float("--fill-factor"),
        1.0,
        "the pixels' sensitive fraction of their area, a centred square (with --pixel-pitch-um)",
    ),
    Option("fan_samples", "--fan-samples", _int("--fan-samples"), FAN_SAMPLES, "pupil positions across each fan"),
    Option("rings", "--rings", _int("--rings"), SPOT_RINGS, "rings of the hexapolar pupil pattern"),
    Option(
        "zernike",
        "--zernike",
        str,
        ZERNIKE,
        "Zernike polynomials: " + "; ".join(f"{k}: {v}" for k, v in ZERNIKE_KINDS.items()),
        tuple(ZERNIKE_KINDS),
    ),
    Option("zernike_terms", "--zernike-terms", _int("--zernike-terms"), ZERNIKE_TERMS, "Zernike terms fitted"),
    Option(
        "energy_reference",
        "--energy-reference",
        str,
        ENERGY_REFERENCES[0],
        "centre of the circles and squares: the PSF's centroid or the chief ray",
        ENERGY_REFERENCES,
    ),
)


def command_options(args, keywords: tuple[str, ...]) -> dict[str, Any]:
    """The options `keywords` given in parsed `args`, read, as keyword arguments (those not given left
    out: the Python function's defaults apply)."""
    values = {k: OPTIONS[k].value(args) for k in keywords}
    return {k: v for k, v in values.items() if v is not None}
