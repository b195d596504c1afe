"""What every surface shape answers (`Shape`), in the frame of its own vertex (+z toward the image, the
vertex at the origin, the surface tangent to z = 0 there): its sag z(x, y) and unit normal at (x, y),
where a ray from the vertex plane meets it, its curvature about the axis when it has one, its entries in a
lens file (`table`) and whether it holds a clear aperture (`check_aperture`). NumPy Float64 arrays;
lengths in mm.

A kind with a closed-form intersection overrides `intersect`; the others take Newton's method on
f(t) = t dz − sag(x + t dx, y + t dy) from `seed` (the vertex plane), as the tracer does for aspheres.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from ...errors import SolasError
from ..sag import ASPHERE_TOL_MM

NEWTON_STEPS = 12  # from the vertex plane: quadratic convergence reaches Float64 rounding well before
RIM_ANGLES = 64  # directions in which `check_aperture` looks at the clear aperture's rim


class Shape:
    """A surface shape in its vertex frame (subclasses are frozen dataclasses of their parameters)."""

    kind: ClassVar[str]  # its name in `shapes.KINDS`
    symmetric: ClassVar[bool] = True  # rotationally symmetric about the z axis

    def sag(self, x, y):
        """z (mm) of the surface at (x, y) (NaN where it does not reach)."""
        raise NotImplementedError

    def gradient(self, x, y):
        """(∂z/∂x, ∂z/∂y) of the sag at (x, y)."""
        raise NotImplementedError

    def sag_and_gradient(self, x, y, sqrt):
        """(z, ∂z/∂x, ∂z/∂y) at (x, y) in any array type given its `sqrt` (NumPy's or Dr.Jit's): how the
        Dr.Jit tracer (`tracer_local`) meets the kinds without rotational symmetry (it meets the others itself)."""
        raise NotImplementedError

    def normal(self, x, y):
        """Unit normals (nx, ny, nz) at (x, y): (−∂z/∂x, −∂z/∂y, 1)/|…|, +z at the vertex."""
        gx, gy = self.gradient(x, y)
        nz = 1.0 / np.sqrt(1.0 + gx * gx + gy * gy)
        return -gx * nz, -gy * nz, nz

    @property
    def section_curvatures(self) -> tuple[float, float]:
        """(c_x, c_y), 1/mm: the vertex curvatures of its sections in the x-z and y-z planes."""
        raise NotImplementedError

    @property
    def paraxial_curvature(self) -> float | None:
        """1/mm: its vertex curvature about the axis; None where it has no axis of symmetry."""
        cx, cy = self.section_curvatures
        return cy if self.symmetric and cx == cy else None

    def table(self) -> dict:
        """Its entries in a lens file's [[surface]] row (our TOML's keys)."""
        raise NotImplementedError

    def scaled(self, factor: float) -> Shape:
        """The shape grown by `factor`: z(x, y) → s·z(x/s, y/s) (a kind held whole, `Surface.form`; the
        rotational kinds scale with the surface's radius, conic, aspheric and qbfs entries)."""
        raise NotImplementedError

    def seed(self, x, y, dx, dy, dz):
        """Where Newton's method starts: t = 0, the ray's point on the vertex plane."""
        return np.zeros_like(x)

    def intersect(self, x, y, dx, dy, dz):
        """(t, hit): the ray (x, y, 0) + t (dx, dy, dz) meets the surface at t, for rays whose residual
        |z − sag| after Newton's method is below `ASPHERE_TOL_MM` (a tracer's tolerance)."""
        t = self.seed(x, y, dx, dy, dz)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for _ in range(NEWTON_STEPS):
                px, py = x + t * dx, y + t * dy
                gx, gy = self.gradient(px, py)
                t = t - (t * dz - self.sag(px, py)) / (dz - gx * dx - gy * dy)
            residual = t * dz - self.sag(x + t * dx, y + t * dy)
            return t, np.isfinite(t) & (np.abs(residual) < ASPHERE_TOL_MM)

    def check_aperture(self, semi_diameter: float, ident: str) -> None:
        """SolasError naming the surface when the shape does not reach its clear aperture's rim (its sag
        is not finite somewhere on the circle of `semi_diameter`)."""
        angle = np.linspace(0.0, 2.0 * math.pi, RIM_ANGLES, endpoint=False)
        with np.errstate(invalid="ignore"):
            z = self.sag(semi_diameter * np.cos(angle), semi_diameter * np.sin(angle))
        if not np.isfinite(z).all():
            raise SolasError(
                f"{ident}: the {self.kind} closes before the clear semi-diameter {semi_diameter:g} mm; "
                "it cannot hold that aperture (a smaller diameter, or larger radii)"
            )
