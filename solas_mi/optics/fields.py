"""Field types: what a field (x, y) in degrees means for a lens, one strategy per kind, chosen once
per lens (`field_type_for`, read as `Lens.field_type`); modules ask the strategy instead of testing
the kind (optiland's optiland/fields/field_types/ is the model).

- `AngleField` (`ANGLE`): field tangents, the incoming direction ∝ (tan x, tan y, 1); each angle below
  89° in magnitude. Lenses of a half field below POLAR_FIELD_DEG.
- `PolarField` (`POLAR`): the incoming direction has polar angle θ = hypot(x, y) from the axis and
  azimuth atan2(y, x), up to and beyond 90° (fisheyes). Lenses of a half field of POLAR_FIELD_DEG or
  more.

On the x and y axes both forms name the same direction. A sensor position is no third kind: psf.sensor
finds the polar angle and azimuth of a chief ray landing there and asks the lens's strategy for the
field of that direction (`FieldType.field_of`). Light module: NumPy only.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import SolasError

# Lenses whose half field (degrees) reaches this take polar fields
POLAR_FIELD_DEG = 89.0


class FieldType:
    """How a lens names its fields; see the module docstring. Subclasses set the attributes."""

    name = ""
    description = ""
    # the incoming rays may meet surface 1 travelling sideways or backwards (fields at 90° and beyond):
    # surface 1 is then met from the launch point, aims grow outward from the axis, fields are measured
    # per solid angle, and the rim of surface 1 bounds no aperture
    sideways = False
    # the lens forms a pinhole (rectilinear) image of these fields: cameras and the plugins' units are
    # a pinhole camera's (else the paraxial camera's, and a fisheye's sensor is just pixels)
    pinhole = True
    # the largest polar angle (degrees) of a table of chief rays on the y axis
    largest_deg = 0.0

    def check(self, field_deg) -> tuple[float, float]:
        """A field (x, y) in degrees as two finite floats within this kind's limits; SolasError naming it."""
        try:
            fx, fy = (float(v) for v in field_deg)
        except (TypeError, ValueError):
            raise SolasError(f"field {field_deg!r} must be two angles (x, y) in degrees") from None
        return fx, fy

    def check_lens(self, lens, where: str) -> None:
        """SolasError (prefixed by `where`) when `lens` cannot be traced with fields of this kind."""

    def incoming(self, field_deg: np.ndarray) -> np.ndarray:
        """What a launch needs per field (…, 2) in degrees (`pupil.Bundle`)."""
        raise NotImplementedError

    def field_of(
        self, theta_rad: np.ndarray, cos_phi: np.ndarray, sin_phi: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The field (x, y) in degrees of the direction of polar angle θ (radians) and azimuth φ."""
        raise NotImplementedError

    def polar(self, field_deg) -> tuple[float, float]:
        """The polar angle θ and azimuth φ (radians, φ from +x counter-clockwise) of a field's direction: the
        inverse of `field_of`."""
        v = self.incoming(np.asarray(field_deg, dtype=np.float64))
        z = v[2] if len(v) == 3 else 1.0  # tangents: the direction ∝ (tan x, tan y, 1)
        return math.atan2(math.hypot(v[0], v[1]), z), math.atan2(v[1], v[0])


class AngleField(FieldType):
    name = "angle"
    description = "field tangents: direction ∝ (tan x, tan y, 1), each angle below 89 deg"
    largest_deg = POLAR_FIELD_DEG - 0.5

    def check(self, field_deg) -> tuple[float, float]:
        fx, fy = super().check(field_deg)
        if not (math.isfinite(fx) and math.isfinite(fy)) or abs(fx) >= 89 or abs(fy) >= 89:
            raise SolasError(f"field ({fx:g}, {fy:g}) deg: each angle must be finite and below 89 deg in magnitude")
        return fx, fy

    def incoming(self, field_deg: np.ndarray) -> np.ndarray:
        """Field tangents (…, 2)."""
        return np.tan(np.radians(np.asarray(field_deg, dtype=np.float64)))

    def field_of(self, theta_rad, cos_phi, sin_phi):
        return np.degrees(np.arctan(np.tan(theta_rad) * cos_phi)), np.degrees(np.arctan(np.tan(theta_rad) * sin_phi))


class PolarField(FieldType):
    name = "polar"
    description = "polar fields: polar angle hypot(x, y), azimuth atan2(y, x), below 180 deg"
    sideways = True
    pinhole = False
    largest_deg = 179.0

    def check(self, field_deg) -> tuple[float, float]:
        fx, fy = super().check(field_deg)
        if not (math.isfinite(fx) and math.isfinite(fy)):
            raise SolasError(f"field ({fx:g}, {fy:g}) deg: each angle must be finite")
        if math.hypot(fx, fy) >= 180:
            raise SolasError(f"field ({fx:g}, {fy:g}) deg: the polar angle hypot(x, y) must be below 180 deg")
        return fx, fy

    def check_lens(self, lens, where: str) -> None:
        """Rays from the side meet surface 1, which the tracer intersects as a whole sphere only."""
        first = lens.surfaces[0]
        if not first.is_sphere:
            raise SolasError(
                f"{where}: surface 1 ({first.label}) is a conic or asphere; a lens of polar fields "
                f"(field_deg {lens.field_deg:g} >= {POLAR_FIELD_DEG:g}) takes rays from the side of its "
                "first surface, which solas-mi intersects as a whole sphere only: make surface 1 "
                f"spherical or flat, or set field_deg below {POLAR_FIELD_DEG:g}"
            )

    def incoming(self, field_deg: np.ndarray) -> np.ndarray:
        """Unit directions (…, 3) of the incoming collimated rays."""
        f = np.radians(np.asarray(field_deg, dtype=np.float64))
        theta, phi = np.hypot(f[..., 0], f[..., 1]), np.arctan2(f[..., 1], f[..., 0])
        return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)

    def field_of(self, theta_rad, cos_phi, sin_phi):
        return np.degrees(theta_rad * cos_phi), np.degrees(theta_rad * sin_phi)


ANGLE, POLAR = AngleField(), PolarField()
FIELD_TYPES = {t.name: t for t in (ANGLE, POLAR)}  # by name, as files store it


def field_type_for(half_field_deg: float) -> FieldType:
    """The field type of a lens of half field `half_field_deg` (degrees): the one place it is chosen."""
    return POLAR if half_field_deg >= POLAR_FIELD_DEG else ANGLE
