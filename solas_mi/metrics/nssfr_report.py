"""What a natural-scene SFR measures (`nssfr.natural_scene_sfr`): each edge ROI (`RoiMeasurement`), MTF50
statistics per annulus (`AnnulusStats`) and the report of an image or a before/after pair (`NsSfrReport`).

ROIs are (x, y, w, h) in px; radii are fractions of R, the centre-to-corner distance; MTF50 in cy/px.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import SolasError
from .annuli import ANNULUS_NAMES, corner_radius
from .esfr import EsfrResult
from .roi import Roi

CURVE_FREQ = np.linspace(0.0, 0.5, 51)  # cy/px, grid of the per-annulus mean SFR curves


@dataclass
class RoiMeasurement:
    """One edge ROI: box (x, y, w, h) px, radius as a fraction of R, annulus index, results."""

    roi: Roi
    radius: float
    annulus: int
    before: EsfrResult
    after: EsfrResult | None = None


@dataclass
class AnnulusStats:
    """MTF50 statistics (cy/px) of one annulus r_inner ≤ r/R < r_outer; curve: mean SFR on CURVE_FREQ."""

    name: str
    r_inner: float
    r_outer: float
    count: int
    mean_mtf50: float | None
    median_mtf50: float | None
    sharpest10_mtf50: float | None
    curve: np.ndarray | None

    @staticmethod
    def of(name: str, r_inner: float, r_outer: float, results: list[EsfrResult]) -> AnnulusStats:
        """Statistics of the valid e-SFR results of one annulus (radii as fractions of R)."""
        values = np.sort([r.mtf50 for r in results])[::-1]
        if values.size == 0:
            return AnnulusStats(name, r_inner, r_outer, 0, None, None, None, None)
        top = values[: max(1, math.ceil(0.1 * values.size))]
        curve = np.mean([np.interp(CURVE_FREQ, r.freq, r.sfr) for r in results], axis=0)
        return AnnulusStats(
            name,
            r_inner,
            r_outer,
            int(values.size),
            float(values.mean()),
            float(np.median(values)),
            float(top.mean()),
            curve,
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict: MTF50 values in cy/px, "mean_sfr" on CURVE_FREQ (rounded to 6 decimals)."""
        return {
            "name": self.name,
            "r_inner": self.r_inner,
            "r_outer": self.r_outer,
            "count": self.count,
            "mean_mtf50": self.mean_mtf50,
            "median_mtf50": self.median_mtf50,
            "sharpest10_mtf50": self.sharpest10_mtf50,
            "mean_sfr": None if self.curve is None else [round(float(v), 6) for v in self.curve],
        }


@dataclass
class NsSfrReport:
    """Natural-scene SFR of one image, or of a before/after pair measured on the same ROIs.

    shape: (rows, columns) px; scheme: the annuli scheme; before/after: statistics per annulus
    (MTF50 in cy/px); rejected: count of rejected ROIs per reason.
    """

    shape: tuple[int, int]
    scheme: str
    mode: str
    rois: list[RoiMeasurement]
    before: list[AnnulusStats]
    after: list[AnnulusStats] | None = None
    rejected: dict[str, int] = field(default_factory=dict)

    @property
    def radius_px(self) -> float:
        """R: distance from the image centre to a corner, px."""
        return corner_radius(*self.shape[:2])

    def mean_change(self) -> list[float | None]:
        """Per annulus: mean of (after − before) MTF50 over identical ROIs, cy/px."""
        if self.after is None:
            raise SolasError("no comparison image was measured")
        out: list[float | None] = []
        for i in range(len(self.before)):
            d = [m.after.mtf50 - m.before.mtf50 for m in self.rois if m.annulus == i and m.after]
            out.append(float(np.mean(d)) if d else None)
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict: R in px, frequencies in cy/px, MTF50 in cy/px, angles in degrees, ROIs in px."""
        out: dict[str, Any] = {
            "shape": list(self.shape),
            "annuli_scheme": self.scheme,
            "mode": self.mode,
            "radius_px": self.radius_px,
            "freq_cy_px": [round(float(f), 6) for f in CURVE_FREQ],
            "annuli": [s.to_dict() for s in self.before],
            "rejected": self.rejected,
        }
        if self.after is not None:
            out["annuli_after"] = [s.to_dict() for s in self.after]
            out["mean_change_mtf50"] = self.mean_change()
        out["rois"] = [
            {
                "roi": list(m.roi),
                "radius": round(m.radius, 4),
                "annulus": ANNULUS_NAMES[m.annulus],
                "mtf50": m.before.mtf50,
                "angle_deg": m.before.angle_deg,
                "orientation": m.before.orientation,
                "contrast": m.before.contrast,
                **({"mtf50_after": m.after.mtf50} if m.after is not None else {}),
            }
            for m in self.rois
        ]
        return out
