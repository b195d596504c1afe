"""What EMVA 1288 (release 4.0) predicts of one linear readout: a charge of μ_e photo-electrons read with
conversion gain K (DN/e⁻), read noise σ_r (e⁻ rms), dark current i_d (e⁻/s) over t seconds and an ADC
that rounds (σ_q² = 1/12 DN², eq. 5).

    σ_d² = σ_r² + i_d t                                  temporal dark noise (e⁻²)
    μ_y.dark = black + K i_d t                           mean dark level (DN)
    σ_y² = K² σ_d² + σ_q² + K (μ_y − μ_y.dark)           photon transfer (eq. 6)
    SNR = μ_e / sqrt(σ_d² + σ_q²/K² + μ_e)               (eq. 15)
    μ_e.min = 1/2 + sqrt(1/4 + σ_d² + σ_q²/K²)           the signal of SNR = 1 (the absolute sensitivity threshold)

Every readout of a sensor's chain, and the flat one-readout sensor, use these."""

import math

import numpy as np

QUANTISATION_VARIANCE = 1.0 / 12.0  # DN², uniform rounding (EMVA 1288 eq. 5)


def dark_variance_e2(read_noise_e: float, dark_current_e_s: float, seconds: float) -> float:
    """σ_d² = σ_r² + i_d t (e⁻²)."""
    return read_noise_e**2 + dark_current_e_s * seconds


def dark_mean_dn(black_dn: float, gain: float, dark_current_e_s: float, seconds: float) -> float:
    """μ_y.dark = black + K i_d t (DN)."""
    return black_dn + gain * dark_current_e_s * seconds


def temporal_variance_dn2(gain: float, dark_e2: float, mean_dn: float, dark_dn: float) -> float:
    """σ_y² = K² σ_d² + σ_q² + K (μ_y − μ_y.dark) (DN², eq. 6) of a mean μ_y over a dark level μ_y.dark."""
    return gain * gain * dark_e2 + QUANTISATION_VARIANCE + gain * (mean_dn - dark_dn)


def snr(electrons: float, gain: float, dark_e2: float) -> float:
    """SNR = μ_e / sqrt(σ_d² + σ_q²/K² + μ_e) (eq. 15)."""
    return electrons / math.sqrt(dark_e2 + QUANTISATION_VARIANCE / gain**2 + electrons)


def threshold_electrons(gain: float, dark_e2: float, extra_e2: float = 0.0) -> float:
    """μ_e.min, the photo-electrons of SNR = 1: the root of μ = sqrt(σ_d² + σ_q²/K² + σ_x² + μ), with σ_x²
    (`extra_e2`) the noise a later stage adds, in e⁻² of this readout."""
    return 0.5 + math.sqrt(0.25 + dark_e2 + QUANTISATION_VARIANCE / gain**2 + extra_e2)


def saturation_dn(gain: float, full_well_e: float, white_dn: int, black_dn: int) -> float:
    """y_sat: the signal above black (DN) of a saturated pixel, min(K · full well, white − black): the well or
    the ADC, whichever fills first."""
    return float(min(gain * full_well_e, white_dn - black_dn))


def saturation_spread_dn(gain: float, read_noise_e: float, dsnu_e: float) -> float:
    """How far below y_sat a saturated pixel may read (DN): 3 σ of the readout noise (read noise and DSNU)
    and the rounding."""
    return 3.0 * gain * float(np.hypot(read_noise_e, dsnu_e)) + 1.0
