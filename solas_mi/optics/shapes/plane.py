"""The plane z = 0 (a flat surface: `radius` = 0 and no other terms)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import Shape


@dataclass(frozen=True)
class Plane(Shape):
    """A flat surface: every ray from the vertex plane is on it (t = 0)."""

    kind = "plane"

    def sag(self, x, y):
        return np.zeros_like(np.asarray(x, dtype=np.float64) + y)

    def gradient(self, x, y):
        zero = self.sag(x, y)
        return zero, zero

    @property
    def section_curvatures(self) -> tuple[float, float]:
        return 0.0, 0.0

    def table(self) -> dict:
        return {"radius": 0.0}

    def intersect(self, x, y, dx, dy, dz):
        return np.zeros_like(x), np.ones(np.shape(x), dtype=bool)
