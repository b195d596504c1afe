"""The even asphere: a conic plus Σ_i A_2i r^2i (i ≥ 2), `aspheric` = [A4, A6, …] (mm^(1−2i)); met by
Newton's method from the conic root (`sag.ASPHERE_ITERATIONS` steps, the tracer's)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..sag import ASPHERE_ITERATIONS, ASPHERE_TOL_MM, sag
from .conic import Conic


@dataclass(frozen=True)
class EvenAsphere(Conic):
    """A conic of vertex `radius` (mm) and `conic` with the even terms `aspheric`."""

    aspheric: tuple[float, ...] = ()
    kind = "asphere"

    def terms(self) -> dict:
        return {**super().terms(), "aspheric": self.aspheric}

    def table(self) -> dict:
        return {"radius": self.radius, "conic": self.conic, "aspheric": list(self.aspheric)}

    def intersect(self, x, y, dx, dy, dz):
        t, _ = super().intersect(x, y, dx, dy, dz)
        terms = self.terms()
        with np.errstate(invalid="ignore", divide="ignore"):
            for _ in range(ASPHERE_ITERATIONS):
                px, py = x + t * dx, y + t * dy
                gx, gy = self.gradient(px, py)
                t = t - (t * dz - sag(px * px + py * py, **terms)) / (dz - gx * dx - gy * dy)
            px, py = x + t * dx, y + t * dy
            r2 = px * px + py * py
            residual = t * dz - sag(r2, **terms)
        inside = (1.0 + self.conic) * self.curvature**2 * r2 <= 1.0  # within the conic's domain, as the tracer
        return t, inside & (np.abs(residual) < ASPHERE_TOL_MM) & np.isfinite(t)
