"""A sphere or conic of revolution: z = c r² / (1 + √(1 − (1 + k) c² r²)), c = 1/`radius`, k = `conic`
(`sag.sag`, the formula every tracer takes). Its ray intersection in closed form: the root nearest the
vertex of A t² − 2B t + C = 0 in the cancellation-free form t = C / (B + √(B² − AC)) (`tracer`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..sag import sag, sag_slope
from .base import Shape


@dataclass(frozen=True)
class Conic(Shape):
    """A sphere (`conic` 0) or conic of revolution of vertex `radius` (mm)."""

    radius: float
    conic: float = 0.0
    kind = "conic"

    @property
    def curvature(self) -> float:
        return 0.0 if self.radius == 0.0 else 1.0 / self.radius

    def terms(self) -> dict:
        """The keyword arguments of `sag.sag` and `sag.sag_slope` that describe it."""
        return {"curvature": self.curvature, "conic": self.conic}

    def sag(self, x, y):
        return sag(x * x + y * y, **self.terms())

    def gradient(self, x, y):
        slope = 2.0 * sag_slope(x * x + y * y, **self.terms())
        return slope * x, slope * y

    @property
    def section_curvatures(self) -> tuple[float, float]:
        return self.curvature, self.curvature

    def table(self) -> dict:
        return {"radius": self.radius, **({"conic": self.conic} if self.conic else {})}

    def intersect(self, x, y, dx, dy, dz):
        c = self.curvature
        b = dz - c * (x * dx + y * dy)
        cc = c * (x * x + y * y)
        disc = b * b - c * (1.0 + self.conic * dz * dz) * cc
        on = (disc >= 0) & (b > 0)
        with np.errstate(invalid="ignore", divide="ignore"):
            t = cc / (b + np.sqrt(np.maximum(disc, 0.0)))
        return np.where(on, t, 0.0), on
