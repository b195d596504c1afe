"""`Merge`, the stage of an HDR sensor's chain that makes one linear signal of its readouts, and the SNR it
predicts in closed form.

The readouts come in order of falling response: readout i gives G_i = K_i R_i DN per photo-electron of the
reference photodiode over the frame's exposure (K_i its conversion gain, R_i = sensitivity × exposure
ratio its share of the light, `readout`), and G_0 > G_1 > .... Each readout's estimate of the signal, in
DN of the first readout (the merged signal's unit),

    x_i = (y_i − black_i) G_0 / G_i,

is used while readout i reads below `threshold` of its saturation (y_sat,i); above it the next readout
takes over. With `blend` b > 0 the two are mixed over the b below the threshold, weight
w_i = clip((threshold − f_i) / b, 0, 1) of x_i, f_i = (y_i − black_i) / y_sat,i. From the least sensitive
readout up, m ← w_i x_i + (1 − w_i) m; the merged code is round(m + black), clipped to [0, 2^bits − 1]: a
black level (a pedestal), so that the noise of a dark pixel is not clipped at 0.

Where readout i alone is used (no blending), the merged SNR is that readout's (EMVA 1288 eq. 15) at its
μ_e,i = R_i μ_e photo-electrons, with the merged code's rounding (1/12 DN², none where G_0 / G_i is a
whole number: `Merge.rounding_e2`) added in its electrons:

    SNR = μ_e,i / sqrt(σ_d,i² + σ_q²/K_i² + σ_q² (R_i / G_0)² + μ_e,i)      (`Merge.predicted_snr`)

so at each transition the SNR falls by the step from readout i to readout i + 1 (the "SNR dip").
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import SolasError
from . import emva
from .limits import check_adc, check_number
from .readout import Readout, bands

MERGE_BITS = (16, 24)  # the merged signal's bits: data sheets give 20-24; float32 (the RAW's EXR) holds 2^24 exactly


@dataclass(frozen=True)
class Merge:
    """The merged signal's bits, the threshold (a fraction of a readout's saturation) where the next readout
    takes over, the width of the blend below it (0: a hard switch), and the merged signal's black level (a
    pedestal, so that the noise of a dark pixel is not clipped at 0)."""

    bits: int = 24
    threshold: float = 0.9
    blend: float = 0.0
    black_level_dn: int = 64

    def __post_init__(self):
        low, high = MERGE_BITS
        if not isinstance(self.bits, int) or isinstance(self.bits, bool) or not low <= self.bits <= high:
            raise SolasError(
                f"sensor merge bits = {self.bits!r} must be an integer from {low} to {high} (the "
                "merged linear signal; a RAW's float32 holds integers to 2^24 exactly)"
            )
        check_number(
            self.threshold,
            "threshold",
            0.0,
            1.0,
            "the fraction of a readout's saturation where the next readout takes over",
            open_low=True,
            where="sensor merge",
        )
        check_number(
            self.blend,
            "blend",
            0.0,
            self.threshold,
            "the width below the threshold over which two readouts are blended, 0 for a hard switch",
            open_high=True,
            where="sensor merge",
        )
        check_adc(self.bits, self.black_level_dn, where="sensor merge", bits=MERGE_BITS)

    def describe(self) -> dict:
        return asdict(self)

    @property
    def white_level_dn(self) -> int:
        return 2**self.bits - 1

    def check_readouts(self, readouts: tuple[Readout, ...]) -> None:
        """The readouts come in order of falling response G_i = K_i R_i (module docstring)."""
        gains = [r.gain_dn_per_e * r.response for r in readouts]
        for (a, ga), (b, gb) in zip(zip(readouts, gains), zip(readouts[1:], gains[1:])):
            if not gb < ga:
                raise SolasError(
                    f"sensor readout {b.name!r} gives {gb:.6g} DN per reference photo-electron, not "
                    f"less than readout {a.name!r} before it ({ga:.6g}): the merge takes the readouts "
                    "in order of falling response (gain × sensitivity × exposure ratio)"
                )
        need = self.saturation_dn(readouts) + self.black_level_dn
        if need > self.white_level_dn:
            raise SolasError(
                f"sensor merge bits = {self.bits} holds merged codes up to {self.white_level_dn}, below "
                f"the last readout's saturation over black_level_dn ({need:.0f} in DN of the first "
                f"readout); give bits >= {math.ceil(math.log2(need + 1))}"
            )

    def merge(self, readouts: tuple[Readout, ...], frames: list[np.ndarray]) -> np.ndarray:
        """The merged code (H, W, uint32) of the readouts' frames (module docstring), band by band
        (`readout.bands`: the same arithmetic, in the processor's cache)."""
        merged = np.empty(frames[0].shape, dtype=np.uint32)
        for band in bands(merged.shape):
            merged[band] = self._merge(readouts, [frame[band] for frame in frames])
        return merged

    def _merge(self, readouts: tuple[Readout, ...], frames: list[np.ndarray]) -> np.ndarray:
        top = readouts[0].gain_dn_per_e * readouts[0].response
        estimates = [(np.asarray(y, dtype=np.float64) - r.black_level_dn, r) for y, r in zip(frames, readouts)]
        signal, last = estimates[-1]
        merged = signal * (top / (last.gain_dn_per_e * last.response))
        for signal, r in reversed(estimates[:-1]):
            estimate = signal * (top / (r.gain_dn_per_e * r.response))
            if self.blend:
                weight = np.clip((self.threshold * r.saturation_dn - signal) / (self.blend * r.saturation_dn), 0.0, 1.0)
                merged = weight * estimate + (1.0 - weight) * merged
            else:
                merged = np.where(signal < self.threshold * r.saturation_dn, estimate, merged)
        merged += self.black_level_dn
        return np.clip(np.rint(merged), 0, self.white_level_dn).astype(np.uint32)

    def saturation_dn(self, readouts: tuple[Readout, ...]) -> float:
        """The merged code at saturation: the last readout's saturation in merged DN (within the merged
        signal's bits: `check_readouts`)."""
        last, top = readouts[-1], readouts[0].gain_dn_per_e * readouts[0].response
        return float(last.saturation_dn * top / (last.gain_dn_per_e * last.response))

    def predicted_snr(self, readouts: tuple[Readout, ...], electrons: float, exposure_s: float) -> float:
        """The merged signal's SNR (no blending) for `electrons` mean photo-electrons of the reference
        photodiode over the frame's exposure `exposure_s` (module docstring): that of the first readout whose
        mean signal lies below the threshold, with the merged code's rounding."""
        top = readouts[0].gain_dn_per_e * readouts[0].response
        used = next(
            (
                r
                for r in readouts[:-1]
                if r.gain_dn_per_e * (electrons * r.response + r.dark_current_e_s * exposure_s * r.exposure_ratio)
                < self.threshold * r.saturation_dn
            ),
            readouts[-1],
        )
        return emva.snr(
            electrons * used.response,
            used.gain_dn_per_e,
            used.dark_variance_e2(exposure_s) + self.rounding_e2(used, top),
        )

    @staticmethod
    def rounding_e2(readout: Readout, top: float) -> float:
        """The merged code's rounding noise in e⁻² of `readout`: σ_q² (R_i / G_0)² where its estimates x_i, integer
        multiples of G_0 / G_i DN, fall between codes; none where G_0 / G_i is a whole number (the first readout,
        exposure ratios of powers of 2), whose estimates are codes already.

        Parameters
        ----------
        readout : Readout
            The readout in use.
        top : float
            G_0, the first readout's DN per reference photo-electron.

        Returns
        -------
        float
            The variance (e⁻²).
        """
        scale = top / (readout.gain_dn_per_e * readout.response)
        return 0.0 if scale == round(scale) else emva.QUANTISATION_VARIANCE * (readout.response / top) ** 2
