"""The cylinder: curved in the y-z plane only, z = c y² / (1 + √(1 − (1 + k) c² y²)) (c = 1/`radius`,
k = `conic`), straight along x: a `toroid.Toroid` without rotation or terms. A cylinder curved in x is
one turned by a frame's tilt about z (`placement`)."""

from __future__ import annotations

from dataclasses import dataclass

from .base import Shape
from .toroid import Toroid


@dataclass(frozen=True)
class Cylinder(Shape):
    """A cylinder of `radius` (mm) and `conic` in the y-z plane, its axis along x."""

    radius: float
    conic: float = 0.0
    kind = "cylinder"
    symmetric = False

    @property
    def toroid(self) -> Toroid:
        """The same surface as a toroid (no rotation, no terms)."""
        return Toroid(self.radius, self.conic)

    def sag(self, x, y):
        return self.toroid.sag(x, y)

    def gradient(self, x, y):
        return self.toroid.gradient(x, y)

    def sag_and_gradient(self, x, y, sqrt):
        return self.toroid.sag_and_gradient(x, y, sqrt)

    @property
    def section_curvatures(self) -> tuple[float, float]:
        return self.toroid.section_curvatures

    def scaled(self, factor: float) -> Cylinder:
        return Cylinder(self.radius * factor, self.conic)

    def table(self) -> dict:
        return {"radius": self.radius, "conic": self.conic}
