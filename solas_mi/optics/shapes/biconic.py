"""The biconic (Zemax's BICONICX without its polynomial terms): z = (c_x x² + c_y y²) / (1 + √(1 − B)),
B = (1 + k_x) c_x² x² + (1 + k_y) c_y² y², with c_y = 1/`radius`, k_y = `conic`, c_x = 1/`radius_x`,
k_x = `conic_x` (a radius 0: flat in that section). Its gradient: ∂z/∂x = 2c_x x/D + A ∂B/∂x / (2 S D²)
with A the numerator, S = √(1 − B), D = 1 + S (the same in y). Met by Newton's method from the vertex
plane. (Not the sum of two conics, z_x(x) + z_y(y), that some tools call biconic: the two agree only
to second order.)"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import Shape


@dataclass(frozen=True)
class Biconic(Shape):
    """A biconic of y-z `radius` and `conic`, x-z `radius_x` and `conic_x` (mm; radius 0: flat)."""

    radius: float
    conic: float = 0.0
    radius_x: float = 0.0
    conic_x: float = 0.0
    kind = "biconic"
    symmetric = False

    @property
    def section_curvatures(self) -> tuple[float, float]:
        return (0.0 if self.radius_x == 0.0 else 1.0 / self.radius_x, 0.0 if self.radius == 0.0 else 1.0 / self.radius)

    def _parts(self, x, y, sqrt=np.sqrt):
        """(A, B, S) at (x, y)."""
        (cx, cy), x2, y2 = self.section_curvatures, x * x, y * y
        b = (1.0 + self.conic_x) * cx * cx * x2 + (1.0 + self.conic) * cy * cy * y2
        with np.errstate(invalid="ignore"):
            return cx * x2 + cy * y2, b, sqrt(1.0 - b)

    def sag(self, x, y):
        a, _, s = self._parts(x, y)
        return a / (1.0 + s)

    def gradient(self, x, y):
        return self.sag_and_gradient(x, y)[1:]

    def sag_and_gradient(self, x, y, sqrt=np.sqrt):
        (cx, cy), (a, _, s) = self.section_curvatures, self._parts(x, y, sqrt)
        d = 1.0 + s
        with np.errstate(invalid="ignore", divide="ignore"):
            bend = a / (2.0 * s * d * d)
        gx = 2.0 * cx * x / d + bend * 2.0 * (1.0 + self.conic_x) * cx * cx * x
        gy = 2.0 * cy * y / d + bend * 2.0 * (1.0 + self.conic) * cy * cy * y
        return a / d, gx, gy

    def scaled(self, factor: float) -> Biconic:
        return Biconic(self.radius * factor, self.conic, self.radius_x * factor, self.conic_x)

    def table(self) -> dict:
        return {"radius": self.radius, "conic": self.conic, "radius_x": self.radius_x, "conic_x": self.conic_x}
