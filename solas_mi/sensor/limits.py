"""The sensor's numbers: the range each may take, the value each takes when left out, and the one check
that names a bad one (every stage of the chain and the flat `[sensor]` table use them).

Each range is wide enough for every sensor made and narrow enough that every value of the signal chain
stays finite (photons per pixel, NumPy's Poisson means, DN)."""

import math

from ..errors import SolasError
from ..render.response import SRGB_RANGE_NM

ELECTRONS_MAX = 1e9  # e⁻ (e⁻/s for the dark current): 1000 × the largest full wells made (scientific CCDs, ~1e6 e⁻)
RANGES = {
    "pixel_pitch_um": (
        0.1,
        1000.0,
        "the pixel pitch in µm: from 0.1 µm, a quarter of violet light's wavelength, "
        "to 1 mm, 5 × an X-ray flat panel's pixel",
    ),
    "dark_current_e_s": (0.0, ELECTRONS_MAX, "the dark current in e⁻/s"),
    "read_noise_e": (0.0, ELECTRONS_MAX, "the read noise in e⁻ rms"),
    "dsnu_e": (0.0, ELECTRONS_MAX, "the spread of the pixel offset in e⁻"),
    "full_well_e": (1.0, ELECTRONS_MAX, "the full-well capacity in e⁻, at least one electron"),
    "wavelengths_nm": (*SRGB_RANGE_NM, "a wavelength in nm within the visible range the RGB image stands for"),
}
PRNU_MEANING = "the relative spread of the pixel gain, e.g. 0.01 for 1 %"
# the values a readout (or the flat table) takes for what it leaves out
READOUT_DEFAULTS = {
    "dark_current_e_s": 10.0,
    "read_noise_e": 3.0,
    "prnu": 0.01,
    "dsnu_e": 1.0,
    "full_well_e": 10000.0,
    "gain_dn_per_e": 0.25,
}
ADC_DEFAULTS = {"bit_depth": 12, "black_level_dn": 64}
ADC_BITS = (8, 16)  # the bit depths of a readout's ADC


def is_number(value) -> bool:
    """A finite real number (not a bool)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def check_number(
    value,
    field: str,
    least: float,
    most: float,
    what: str,
    *,
    open_low: bool = False,
    open_high: bool = False,
    where: str = "sensor",
) -> None:
    """SolasError ("`where` `field` = value must be a number in [least, most] (what)") unless `value` is a
    real number in the interval from `least` to `most` (open at an end where `open_low`, `open_high`)."""
    if (
        not is_number(value)
        or value < least
        or value > most
        or (open_low and value == least)
        or (open_high and value == most)
    ):
        interval = f"{'(' if open_low else '['}{least:g}, {most:g}{')' if open_high else ']'}"
        raise SolasError(f"{where} {field} = {value!r} must be a number in {interval} ({what})")


def check_ranged(value, field: str, where: str = "sensor") -> None:
    """`check_number` with the field's range and meaning from RANGES."""
    check_number(value, field, *RANGES[field], where=where)


def check_adc(bit_depth, black_level_dn, where: str = "sensor", bits: tuple[int, int] = ADC_BITS) -> None:
    """An ADC's bit depth (an integer in `bits`) and black level (an integer below its white level)."""
    low, high = bits
    if not isinstance(bit_depth, int) or isinstance(bit_depth, bool) or not low <= bit_depth <= high:
        raise SolasError(f"{where} bit_depth = {bit_depth!r} must be an integer from {low} to {high}")
    top = 2**bit_depth - 1
    if not isinstance(black_level_dn, int) or isinstance(black_level_dn, bool) or not 0 <= black_level_dn < top:
        raise SolasError(
            f"{where} black_level_dn = {black_level_dn!r} must be an integer from 0 to {top - 1} "
            f"(below the {bit_depth}-bit ADC's white level)"
        )


def check_gain(gain_dn_per_e, full_well_e: float, bit_depth: int, where: str = "sensor") -> None:
    """A conversion gain (DN/e⁻) that an ADC of `bit_depth` bits reads: at most its white level (one electron
    fills it), and at least one code across the full well (a smaller gain reads every pixel as black)."""
    top = 2**bit_depth - 1
    check_number(
        gain_dn_per_e,
        "gain_dn_per_e",
        0.0,
        float(top),
        "the conversion gain in DN/e⁻, at most the ADC's white level: one electron fills the ADC",
        open_low=True,
        where=where,
    )
    if gain_dn_per_e * full_well_e < 1.0:
        raise SolasError(
            f"{where} gain_dn_per_e = {gain_dn_per_e!r} times full_well_e = {full_well_e!r} "
            f"must be at least 1 DN (the full well spans at least one ADC code; else every pixel "
            "reads black)"
        )
