"""`SensorModel`: the parameters of a camera sensor in the terms of EMVA 1288 (release 4.0), checked on
construction, and the photon-transfer predictions they make.

Temporal noise in electrons: shot noise of the photo-electrons (variance μ_e), dark current (Poisson,
mean and variance i_d t) and read noise σ_r (Gaussian), so σ_d² = σ_r² + i_d t. The conversion gain K
(DN/e⁻) and the ADC's rounding (σ_q² = 1/12 DN²) give the photon-transfer line (EMVA 1288 eq. 6)
    σ_y² = K² σ_d² + σ_q² + K (μ_y − μ_y.dark),   μ_y.dark = black + K i_d t,
and the SNR (eq. 15) SNR = μ_e / sqrt(σ_d² + σ_q²/K² + μ_e). PRNU (relative spread of the per-pixel
gain) and DSNU (spread of the per-pixel offset, e⁻) are spatial: fixed by the seed, not temporal.
"""

from dataclasses import dataclass, fields
from functools import cached_property

import numpy as np

from ..errors import SolasError
from . import emva
from .limits import ADC_DEFAULTS, PRNU_MEANING, READOUT_DEFAULTS, check_adc, check_gain, check_number, check_ranged
from .photons import SCALAR_DEFAULTS, PhotonConversion
from .qe import QECurve


@dataclass(frozen=True)
class SensorModel:
    """A camera sensor of one linear readout in the terms of EMVA 1288, checked when built ([the sensor](../details/sensor.md)).

    Quantum efficiency is given per filter (R, G, B, clear) with the wavelength that stands for each of the
    image's three channels, or instead as a QE curve per filter. The scalar fields left out take
    `SCALAR_DEFAULTS`; `files.load_sensor` reads one from a preset or a TOML file. Its chain of stages
    (photons → one readout) is `chain.chain_of`; an HDR sensor is a `chain.SensorChain` of several.

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
    qe_r: float | None = None  # default 0.6 (SCALAR_DEFAULTS), None with a qe_curve
    qe_g: float | None = None  # 0.7
    qe_b: float | None = None  # 0.5
    qe_c: float | None = None  # 0.8
    wavelengths_nm: tuple[float, float, float] | None = None  # (610, 540, 465)
    dark_current_e_s: float = READOUT_DEFAULTS["dark_current_e_s"]
    read_noise_e: float = READOUT_DEFAULTS["read_noise_e"]
    prnu: float = READOUT_DEFAULTS["prnu"]
    dsnu_e: float = READOUT_DEFAULTS["dsnu_e"]
    full_well_e: float = READOUT_DEFAULTS["full_well_e"]
    gain_dn_per_e: float = READOUT_DEFAULTS["gain_dn_per_e"]
    bit_depth: int = ADC_DEFAULTS["bit_depth"]
    black_level_dn: int = ADC_DEFAULTS["black_level_dn"]
    cfa: str = "RGGB"
    qe_curve: QECurve | None = None

    def __post_init__(self):
        for name in SCALAR_DEFAULTS:  # the photon conversion fills the scalar fields left out
            object.__setattr__(self, name, getattr(self.photons, name))
        for name in ("dark_current_e_s", "read_noise_e", "dsnu_e", "full_well_e"):
            check_ranged(getattr(self, name), name)
        check_number(self.prnu, "prnu", 0.0, 1.0, PRNU_MEANING, open_high=True)
        check_adc(self.bit_depth, self.black_level_dn)
        check_gain(self.gain_dn_per_e, self.full_well_e, self.bit_depth)

    @cached_property
    def photons(self) -> PhotonConversion:
        """The photon conversion: pitch, quantum efficiencies and CFA (checked when the model is made)."""
        return PhotonConversion(**{name: getattr(self, name) for name in PhotonConversion.field_names()})

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
        return emva.saturation_dn(self.gain_dn_per_e, self.full_well_e, self.white_level_dn, self.black_level_dn)

    @property
    def saturation_e(self) -> float:
        """The photo-electrons at saturation: y_sat / K."""
        return self.saturation_dn / self.gain_dn_per_e

    def linear_dn(self, raw: np.ndarray) -> np.ndarray:
        """The signal above black of a RAW frame (as `chain.SensorChain.linear_dn`).

        Parameters
        ----------
        raw : numpy.ndarray
            A RAW frame of this sensor (DN).

        Returns
        -------
        numpy.ndarray
            float64 DN above the black level.
        """
        return np.asarray(raw, dtype=np.float64) - self.black_level_dn

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
        spread = emva.saturation_spread_dn(self.gain_dn_per_e, self.read_noise_e, self.dsnu_e)
        return np.asarray(raw) >= self.black_level_dn + self.saturation_dn - spread

    @property
    def channel_wavelengths_nm(self) -> tuple[float, ...]:
        """The wavelength (nm) that stands for each image channel R, G, B: `wavelengths_nm`, or with a QE
        curve the centres of the channels' bands (`PhotonConversion`)."""
        return self.photons.channel_wavelengths_nm

    def effective_qe(self) -> np.ndarray:
        """The electrons per photon of each image channel on a pixel of each filter (`qe` module).

        Returns
        -------
        numpy.ndarray
            Q[f, c], 4 × 3: filters in `cfa.FILTERS` order, channels R, G, B (at
            `channel_wavelengths_nm`).
        """
        return self.photons.effective_qe()

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
        return emva.dark_variance_e2(self.read_noise_e, self.dark_current_e_s, exposure_s)

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
        return emva.dark_mean_dn(self.black_level_dn, self.gain_dn_per_e, self.dark_current_e_s, exposure_s)

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
        return emva.temporal_variance_dn2(
            self.gain_dn_per_e, self.dark_variance_e2(exposure_s), mean_dn, self.dark_mean_dn(exposure_s)
        )

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
        return emva.snr(electrons, self.gain_dn_per_e, self.dark_variance_e2(exposure_s))
