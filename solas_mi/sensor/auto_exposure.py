"""Auto-exposure: the exposure time that puts a stated percentile of a frame's pixels at a stated fraction
of the sensor's saturation, chosen from the irradiance before the frame is taken (as a camera's
auto-exposure meters the scene).

A pixel's mean electrons grow linearly with the exposure t: μ_e(t) = (r + i_d) t, with r its photo-electrons
per second (`capture.mean_electrons` at t = 1 s: QE, CFA and pixel area, before PRNU) and i_d the dark
current. With r_P the P-th percentile of r over the frame's pixels and e_sat the saturation in electrons
(`SensorModel.saturation_e`: the full well, or the ADC's range if that is smaller; an HDR sensor's: its
reference photodiode's electrons where its last readout saturates, `chain.SensorChain.saturation_e`), the exposure

    t = F e_sat / (r_P + i_d)

puts the P-th percentile's mean signal at the fraction F of saturation; the pixels above it are the
(100 − P) % that may clip. A frame with no light at that percentile has no such exposure (refused).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from .chain import SensorChain
from .model import SensorModel

AUTO = "auto"  # how an exposure is asked to be chosen: "auto", or "auto:P,F"


@dataclass(frozen=True)
class AutoExposure:
    """Put the `percentile`-th percentile (0 < P <= 100) of the pixels' mean signal at `fraction`
    (0 < F <= 1) of saturation."""

    percentile: float = 99.0
    fraction: float = 0.8

    def __post_init__(self):
        for name, value, low, high in (
            ("percentile", self.percentile, 0.0, 100.0),
            ("fraction", self.fraction, 0.0, 1.0),
        ):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not low < value <= high:
                raise SolasError(f"auto-exposure {name} {value!r} must be a number in ({low:g}, {high:g}]")

    def describe(self) -> dict:
        return {"percentile": self.percentile, "fraction": self.fraction}

    def choose(self, model: SensorModel | SensorChain, irradiance: np.ndarray) -> tuple[float, dict]:
        """The exposure (s) for an irradiance image (H, W, 3, W/m²), and what it was chosen from (metadata)."""
        from .capture import mean_electrons

        try:
            per_second = mean_electrons(model, irradiance, 1.0)
        except SolasError:  # the light of one second (an image checked finite and >= 0) passes a float64
            raise SolasError(
                f"auto-exposure: irradiance up to {float(np.max(irradiance)):.3g} W/m² gives more "
                "photo-electrons per second than a float64 holds (1.8e308); give a smaller --scale"
            ) from None
        rate = float(np.percentile(per_second, self.percentile))
        if not rate > 0:
            raise SolasError(
                f"auto-exposure: the {self.percentile:g}th percentile of the frame's pixels gets no light "
                "(0 photo-electrons/s); give --exposure-ms in ms, or a lower percentile"
            )
        saturation_e = model.saturation_e
        seconds = self.fraction * saturation_e / (rate + model.dark_current_e_s)
        return seconds, {
            **self.describe(),
            "percentile_e_per_s": rate,
            "saturation_e": saturation_e,
            "exposure_ms": seconds * 1e3,
        }


def exposure_seconds(
    exposure: float | AutoExposure, model: SensorModel | SensorChain, irradiance: np.ndarray
) -> tuple[float, dict]:
    """The exposure (s) of a frame: `exposure` ms as given, or chosen from the irradiance (`AutoExposure`),
    with what it was chosen from ({} when given)."""
    if isinstance(exposure, AutoExposure):
        return exposure.choose(model, irradiance)
    return exposure * 1e-3, {}


def parse_exposure(text, flag: str = "--exposure-ms") -> float | AutoExposure:
    """An exposure in ms (a number > 0, finite), or "auto" / "auto:P,F" (`AutoExposure`)."""
    if isinstance(text, AutoExposure):
        return text
    word = str(text).strip()
    if word == AUTO or word.startswith(AUTO + ":"):
        parts = word[len(AUTO) + 1 :].split(",") if word != AUTO else []
        try:
            values = [float(p) for p in parts]
        except ValueError:
            values = []
        if len(values) != len(parts) or len(values) not in (0, 2):
            raise SolasError(
                f"{flag} {text!r} must be a time in ms, {AUTO}, or {AUTO}:P,F (percentile P of the "
                "pixels at fraction F of saturation, e.g. auto:99,0.8)"
            )
        return AutoExposure(*values)
    try:
        value = float(word)
    except ValueError:
        raise SolasError(f"{flag} {text!r} must be a time in ms (a number > 0) or {AUTO}[:P,F]") from None
    if not 0 < value < math.inf:
        raise SolasError(f"{flag} {value} must be > 0 and finite (a time in ms), or {AUTO}[:P,F]")
    return value
