"""The toroid (Zemax's TOROIDAL, optiland's toroidal geometry): a curve in the y-z plane,
z_y(y) = c y² / (1 + √(1 − (1 + k) c² y²)) + Σ_i α_i y^2i (i ≥ 1; c = 1/`radius`, k = `conic`,
`terms_y` = [α1, α2, …], mm^(1−2i)), rotated about the axis parallel to y through z = R
(`radius_rotation`, mm; 0: no rotation, the curve swept along x, a cylinder). A point lies on it where
(R − z)² + x² = (R − z_y)², so z = z_y + x² / (a + sgn(a) √(a² − x²)) with a = R − z_y (the
cancellation-free form of R − sgn(a) √(a² − x²)), and the gradient ∂z/∂x = x / (R − z),
∂z/∂y = (R − z_y) z_y′ / (R − z). Met by Newton's method from the vertex plane."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import Shape


@dataclass(frozen=True)
class Toroid(Shape):
    """A toroid: the y-z curve of vertex `radius` (mm), `conic` and `terms_y`, rotated at `radius_rotation`
    (mm; 0: a cylinder)."""

    radius: float
    conic: float = 0.0
    terms_y: tuple[float, ...] = ()
    radius_rotation: float = 0.0
    kind = "toroid"
    symmetric = False

    @property
    def curvature(self) -> float:
        """1/mm: the y-z curve's base curvature 1/`radius` (0 for radius 0)."""
        return 0.0 if self.radius == 0.0 else 1.0 / self.radius

    def profile(self, y, sqrt=np.sqrt):
        """(z_y, dz_y/dy) of the y-z curve."""
        c, y2 = self.curvature, y * y
        with np.errstate(invalid="ignore", divide="ignore"):
            root = sqrt(1.0 - (1.0 + self.conic) * c * c * y2)
            z, dz = c * y2 / (1.0 + root), c * y / root
        power, odd = y2, y  # y^2i and y^(2i−1)
        for i, a in enumerate(self.terms_y, start=1):
            z, dz = z + a * power, dz + 2.0 * i * a * odd
            power, odd = power * y2, odd * y2
        return z, dz

    def sag(self, x, y):
        return self.sag_and_gradient(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))[0]

    def gradient(self, x, y):
        return self.sag_and_gradient(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))[1:]

    def sag_and_gradient(self, x, y, sqrt=np.sqrt):
        zy, dzy = self.profile(y, sqrt)
        if self.radius_rotation == 0.0:
            return zy, 0.0 * (zy + x), dzy + 0.0 * x
        a = self.radius_rotation - zy
        with np.errstate(invalid="ignore", divide="ignore"):
            root = a / abs(a) * sqrt(a * a - x * x)  # R − z
            z = zy + x * x / (a + root)
            return z, x / root, a * dzy / root

    @property
    def section_curvatures(self) -> tuple[float, float]:
        cx = 0.0 if self.radius_rotation == 0.0 else 1.0 / self.radius_rotation
        return cx, self.curvature + (2.0 * self.terms_y[0] if self.terms_y else 0.0)

    def scaled(self, factor: float) -> Toroid:
        terms = tuple(a * factor ** (1 - 2 * i) for i, a in enumerate(self.terms_y, start=1))
        return Toroid(self.radius * factor, self.conic, terms, self.radius_rotation * factor)

    def table(self) -> dict:
        return {
            "radius": self.radius,
            "conic": self.conic,
            "terms_y": list(self.terms_y),
            "radius_rotation": self.radius_rotation,
        }
