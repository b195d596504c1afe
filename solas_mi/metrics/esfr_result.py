"""`EsfrResult`: the e-SFR of one ROI (`esfr.esfr`) with its diagnostics, each stage of the measurement
filling its part. Frequencies in cycles/px along the edge normal, angles in degrees.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class EsfrResult:
    """e-SFR of one ROI with its diagnostics.

    freq: cy/px along the edge normal (0 … 1/cos θ); sfr: normalised to 1 at f = 0.
    mtf50 / mtf10: cy/px, None when invalid (see `reason`) or when the SFR does not fall to
    0.5 / 0.1 below 0.5 cy/px (mtf50_reason "not found").
    angle_deg: edge tilt θ from the axis it runs along (0–45°, more is warned); orientation: that axis
    ("vertical": the edge runs top to bottom). Empty arrays and no numbers when invalid.
    """

    mode: str
    valid: bool
    reason: str | None = None
    warnings: list[str] = field(default_factory=list)
    freq: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sfr: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mtf50: float | None = None
    mtf10: float | None = None
    mtf50_reason: str | None = None
    angle_deg: float | None = None
    orientation: str | None = None
    contrast: float | None = None  # (p95 − p5)/(p95 + p5) of the denoised ROI
    noise: float | None = None  # noise sd / step height
    step_rows_fraction: float | None = None
    rows_used: int | None = None
    fit_order: int | None = None
    fit_residual_px: float | None = None  # rms distance of row centroids from the fitted edge
    empty_bins: int | None = None
    clipped_fraction: float | None = None
    lsf_width_px: float | None = None  # equivalent width ∫LSF / max LSF, along the normal
    esf: np.ndarray = field(default_factory=lambda: np.zeros(0))  # 4× oversampled, bin = cos θ/4 px

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict of the scalar results and diagnostics, with the SFR curve as
        "freq_cy_px" and "sfr" (rounded to 6 decimals); the ESF is not included."""
        out: dict[str, Any] = {
            k: getattr(self, k)
            for k in (
                "mode",
                "valid",
                "reason",
                "warnings",
                "mtf50",
                "mtf10",
                "mtf50_reason",
                "angle_deg",
                "orientation",
                "contrast",
                "noise",
                "step_rows_fraction",
                "rows_used",
                "fit_order",
                "fit_residual_px",
                "empty_bins",
                "clipped_fraction",
                "lsf_width_px",
            )
        }
        out["freq_cy_px"] = [round(float(v), 6) for v in self.freq]
        out["sfr"] = [round(float(v), 6) for v in self.sfr]
        return out
