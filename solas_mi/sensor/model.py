"""`SensorModel`: the parameters of a camera sensor in the terms of EMVA 1288 (release 4.0), checked on
construction, and the photon-transfer predictions they make.

Temporal noise in electrons: shot noise of the photo-electrons (variance μ_e), dark current (Poisson,
mean and variance i_d t) and read noise σ_r (Gaussian), so σ_d² = σ_r² + i_d t. The conversion gain K
(DN/e⁻) and the ADC's rounding (σ_q² = 1/12 DN²) give the photon-transfer line (EMVA 1288 eq. 6)
    σ_y² = K² σ_d² + σ_q² + K (μ_y − μ_y.dark),   μ_y.dark = black + K i_d t,
and the SNR (eq. 15) SNR = μ_e / sqrt(σ_d² + σ_q²/K² + μ_e). PRNU (relative spread of the per-pixel
gain) and DSNU (spread of the per-pixel offset, e⁻) are spatial: fixed by the seed, not temporal.
"""
import math
from dataclasses import dataclass, fields
from typing import cast

import numpy as np

from ..errors import SolasError
from .cfa import check_pattern
from .qe import BAND_CENTRES_NM, SRGB_RANGE_NM, QECurve, scalar_effective_qe

QUANTISATION_VARIANCE = 1.0 / 12.0  # DN², uniform rounding (EMVA 1288 eq. 5)
# the scalar quantum efficiencies and channel wavelengths (nm) of a sensor described without a QE curve
SCALAR_DEFAULTS = {"qe_r": 0.6, "qe_g": 0.7, "qe_b": 0.5, "qe_c": 0.8, "wavelengths_nm": (610.0, 540.0, 465.0)}


# The range of each number (least, most, what it is): every sensor made lies far inside it, and within it
# every value of the signal chain stays finite (photons per pixel, NumPy's Poisson means, DN).
ELECTRONS_MAX = 1e9  # e⁻ (e⁻/s for the dark current): 1000 × the largest full wells made (scientific CCDs, ~1e6 e⁻)
RANGES = {
    "pixel_pitch_um": (0.1, 1000.0, "the pixel pitch in µm: from 0.1 µm, a quarter of violet light's wavelength, "
                                    "to 1 mm, 5 × an X-ray flat panel's pixel"),
    "dark_current_e_s": (0.0, ELECTRONS_MAX, "the dark current in e⁻/s"),
    "read_noise_e": (0.0, ELECTRONS_MAX, "the read noise in e⁻ rms"),
    "dsnu_e": (0.0, ELECTRONS_MAX, "the spread of the pixel offset in e⁻"),
    "full_well_e": (1.0, ELECTRONS_MAX, "the full-well capacity in e⁻, at least one electron"),
    "wavelengths_nm": (*SRGB_RANGE_NM, "a wavelength in nm within the visible range the RGB image stands for"),
}


def _number(value, field: str, least: float, most: float, what: str, *, open_low: bool = False,
            open_high: bool = False) -> None:
    """SolasError unless `value` is a real number in the interval from `least` to `most` (open at an end
    where `open_low`, `open_high`)."""
    number = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not number or value < least or value > most or (open_low and value == least) or (open_high and value == most):
        interval = f"{'(' if open_low else '['}{least:g}, {most:g}{')' if open_high else ']'}"
        raise SolasError(f"sensor {field} = {value!r} must be a number in {interval} ({what})")


def _ranged(model, field: str) -> None:
    _number(getattr(model, field), field, *RANGES[field])


@dataclass(frozen=True)
class SensorModel:
    """A camera sensor in the terms of EMVA 1288, checked when built ([the sensor](../details/sensor.md)).

    Quantum efficiency is given per filter (R, G, B, clear) with the wavelength that stands for each of the
    image's three channels, or instead as a QE curve per filter. The scalar fields left out take
    `SCALAR_DEFAULTS`; `files.load_sensor` reads one from a preset or a TOML file.

    Parameters
    ----------
    pixel_pitch_um : float, default 3.0
        The pixel pitch (µm).
    qe_r, qe_g, qe_b, qe_c : float, optional
        Quantum efficiency of the R, G, B and clear filters, in (0, 1]; default 0.6, 0.7, 0.5, 0.8; none
        with a `qe_curve`.
    wavelengths_nm : (float, float, float), optional
        The wavelengths (nm) that stand for the image's R, G, B; default (610, 540, 465); none with a
        `qe_curve`.
    dark_current_e_s : float, default 10.0
        Dark current (e⁻/s).
    read_noise_e : float, default 3.0
        Read noise (e⁻ rms).
    prnu : float, default 0.01
        The relative spread of the pixel gain.
    dsnu_e : float, default 1.0
        The spread of the pixel offset (e⁻).
    full_well_e : float, default 10000.0
        The full-well capacity (e⁻).
    gain_dn_per_e : float, default 0.25
        The conversion gain K (DN/e⁻).
    bit_depth : int, default 12
        The ADC's bits, 8 to 16.
    black_level_dn : int, default 64
        The black level (DN).
    cfa : str, default "RGGB"
        The colour filter array's pattern (`cfa`).
    qe_curve : QECurve, optional
        The filters' quantum efficiency against wavelength (`qe.QECurve`).

    Raises
    ------
    SolasError
        For a value out of its range, a QE curve given with scalar efficiencies, or an ADC whose codes
        cannot hold the signal.

    Examples
    --------
    >>> from solas_mi.sensor import SensorModel
    >>> sensor = SensorModel(read_noise_e=2.0)
    >>> sensor.white_level_dn, round(sensor.snr(1000.0, exposure_s=0.01), 2)
    (4095, 31.54)
    """
    pixel_pitch_um: float = 3.0
    qe_r: float | None = None
    qe_g: float | None = None
    qe_b: float | None = None
    qe_c: float | None = None
    wavelengths_nm: tuple[float, float, float] | None = None
    dark_current_e_s: float = 10.0
    read_noise_e: float = 3.0
    prnu: float = 0.01
    dsnu_e: float = 1.0
    full_well_e: float = 10000.0
    gain_dn_per_e: float = 0.25
    bit_depth: int = 12
    black_level_dn: int = 64
    cfa: str = "RGGB"
    qe_curve: QECurve | None = None

    def __post_init__(self):
        _ranged(self, "pixel_pitch_um")
        if self.qe_curve is None:
            self._check_scalar_qe()
        elif not isinstance(self.qe_curve, QECurve):
            raise SolasError(f"sensor qe_curve must be a QECurve, got {type(self.qe_curve).__name__}")
        elif given := [name for name in SCALAR_DEFAULTS if getattr(self, name) is not None]:
            raise SolasError(f"sensor qe_curve and {', '.join(given)} both given: a QE curve replaces the scalar "
                             f"quantum efficiencies and sets the channel wavelengths; give one or the other")
        for name in ("dark_current_e_s", "read_noise_e", "dsnu_e", "full_well_e"):
            _ranged(self, name)
        _number(self.prnu, "prnu", 0.0, 1.0, "the relative spread of the pixel gain, e.g. 0.01 for 1 %", open_high=True)
        check_pattern(self.cfa)
        self._check_adc()
        if self.qe_curve is not None:
            self.qe_curve.check_filters(self.cfa)
            self.qe_curve.check_response(self.cfa)

    def _check_scalar_qe(self) -> None:
        """Fill the scalar fields left out with their defaults and check them."""
        for name, default in SCALAR_DEFAULTS.items():
            if getattr(self, name) is None:
                object.__setattr__(self, name, default)
        for name in ("qe_r", "qe_g", "qe_b", "qe_c"):
            _number(getattr(self, name), name, 0.0, 1.0, "a quantum efficiency", open_low=True)
        if not isinstance(self.wavelengths_nm, (tuple, list)) or len(self.wavelengths_nm) != 3:
            raise SolasError(f"sensor wavelengths_nm = {self.wavelengths_nm!r} must be three wavelengths (R, G, B) in nm")
        for value in self.wavelengths_nm:
            _number(value, "wavelengths_nm", *RANGES["wavelengths_nm"])
        object.__setattr__(self, "wavelengths_nm", tuple(float(v) for v in self.wavelengths_nm))

    def _check_adc(self) -> None:
        """Bit depth, black level and conversion gain: the ADC's codes hold the signal, and the full well
        spans at least one code (a smaller gain reads every pixel as black)."""
        if not isinstance(self.bit_depth, int) or isinstance(self.bit_depth, bool) or not 8 <= self.bit_depth <= 16:
            raise SolasError(f"sensor bit_depth = {self.bit_depth!r} must be an integer from 8 to 16")
        top = self.white_level_dn
        if not isinstance(self.black_level_dn, int) or isinstance(self.black_level_dn, bool) \
                or not 0 <= self.black_level_dn < top:
            raise SolasError(f"sensor black_level_dn = {self.black_level_dn!r} must be an integer from 0 to {top - 1} "
                             f"(below the {self.bit_depth}-bit ADC's white level)")
        _number(self.gain_dn_per_e, "gain_dn_per_e", 0.0, float(top),
                "the conversion gain in DN/e⁻, at most the ADC's white level: one electron fills the ADC", open_low=True)
        if self.gain_dn_per_e * self.full_well_e < 1.0:
            raise SolasError(f"sensor gain_dn_per_e = {self.gain_dn_per_e!r} times full_well_e = {self.full_well_e!r} "
                             f"must be at least 1 DN (the full well spans at least one ADC code; else every pixel "
                             "reads black)")

    @classmethod
    def from_dict(cls, values: dict) -> "SensorModel":
        """A model from a mapping of field names (a TOML table).

        Parameters
        ----------
        values : dict
            Field name → value (lists for tuples, a QE curve as its table of columns).

        Returns
        -------
        SensorModel
            The model, checked.

        Raises
        ------
        SolasError
            For an unknown name or a bad value.
        """
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise SolasError(f"unknown sensor parameter(s) {', '.join(unknown)}; allowed: {', '.join(sorted(known))}")
        values = {k: tuple(v) if isinstance(v, list) else v for k, v in values.items() if v is not None}
        if "qe_curve" in values:
            values["qe_curve"] = QECurve.from_table(values["qe_curve"], "sensor qe_curve")
        return cls(**values)

    @property
    def white_level_dn(self) -> int:
        """The ADC's largest code (DN)."""
        return 2**self.bit_depth - 1

    @property
    def saturation_dn(self) -> float:
        """y_sat: the signal above black (DN) of a saturated pixel, min(K · full well, white − black): the
        well or the ADC, whichever fills first."""
        return float(min(self.gain_dn_per_e * self.full_well_e, self.white_level_dn - self.black_level_dn))

    def saturated(self, raw: np.ndarray) -> np.ndarray:
        """Where a RAW frame is saturated.

        Parameters
        ----------
        raw : numpy.ndarray
            The RAW frame (DN).

        Returns
        -------
        numpy.ndarray
            True where within 3 σ of the readout noise (read noise and DSNU) and the rounding of the
            saturation level.
        """
        spread = 3.0 * self.gain_dn_per_e * float(np.hypot(self.read_noise_e, self.dsnu_e)) + 1.0
        return np.asarray(raw) >= self.black_level_dn + self.saturation_dn - spread

    @property
    def channel_wavelengths_nm(self) -> tuple[float, ...]:
        """The wavelength (nm) that stands for each image channel R, G, B: `wavelengths_nm`, or with a QE
        curve the centres of the channels' bands (`qe` module)."""
        return BAND_CENTRES_NM if self.wavelengths_nm is None else self.wavelengths_nm  # None with a QE curve

    def effective_qe(self) -> np.ndarray:
        """The electrons per photon of each image channel on a pixel of each filter (`qe` module).

        Returns
        -------
        numpy.ndarray
            Q[f, c], 4 × 3: filters in `cfa.FILTERS` order, channels R, G, B (at
            `channel_wavelengths_nm`).
        """
        if self.qe_curve is None:
            # without a QE curve, __post_init__ gave each scalar QE left out its default
            return scalar_effective_qe(cast(dict[str, float], {"R": self.qe_r, "G": self.qe_g, "B": self.qe_b, "C": self.qe_c}))
        return self.qe_curve.effective_qe(set(self.cfa))

    def dark_variance_e2(self, exposure_s: float) -> float:
        """The temporal dark noise σ_d² = σ_r² + i_d t.

        Parameters
        ----------
        exposure_s : float
            The exposure time t (s).

        Returns
        -------
        float
            σ_d² (e⁻²).
        """
        return self.read_noise_e**2 + self.dark_current_e_s * exposure_s

    def dark_mean_dn(self, exposure_s: float) -> float:
        """The mean dark signal μ_y.dark = black + K i_d t.

        Parameters
        ----------
        exposure_s : float
            The exposure time t (s).

        Returns
        -------
        float
            μ_y.dark (DN).
        """
        return self.black_level_dn + self.gain_dn_per_e * self.dark_current_e_s * exposure_s

    def temporal_variance_dn2(self, mean_dn: float, exposure_s: float) -> float:
        """The temporal variance of a pixel's signal below saturation, EMVA 1288 eq. 6:
        σ_y² = K² σ_d² + σ_q² + K (μ_y − μ_y.dark).

        Parameters
        ----------
        mean_dn : float
            The mean signal μ_y (DN).
        exposure_s : float
            The exposure time (s).

        Returns
        -------
        float
            σ_y² (DN²).
        """
        k = self.gain_dn_per_e
        return k * k * self.dark_variance_e2(exposure_s) + QUANTISATION_VARIANCE + k * (mean_dn - self.dark_mean_dn(exposure_s))

    def snr(self, electrons: float, exposure_s: float) -> float:
        """The signal-to-noise ratio, EMVA 1288 eq. 15: SNR = μ_e / sqrt(σ_d² + σ_q²/K² + μ_e).

        Parameters
        ----------
        electrons : float
            The photo-electrons μ_e.
        exposure_s : float
            The exposure time (s).

        Returns
        -------
        float
            The SNR.
        """
        noise = self.dark_variance_e2(exposure_s) + QUANTISATION_VARIANCE / self.gain_dn_per_e**2 + electrons
        return electrons / math.sqrt(noise)
