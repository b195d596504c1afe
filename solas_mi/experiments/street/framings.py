"""Camera poses on the street scene for each lens: what the lens's field sees.

A framing is the camera's origin and target (world metres, `scene` explains the world), its roll
(degrees, so that the street's vertical and horizontal edges are slanted as the SFR needs) and the
near focus distance (m) of the depth experiment and the distance of the far subject (m), where a second
PSF grid is computed. `FRAMINGS` is keyed by lens name; a lens without an
entry takes `NARROW` (half field ≤ NARROW_MAX_DEG: the far end of the street, the doublet's view) or
`WIDE` (the street ahead).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Framing:
    """origin, target: metres; roll_deg: degrees about the view axis; near_focus_m, far_m: metres in front of
    the lens."""

    origin: tuple[float, float, float]
    target: tuple[float, float, float]
    roll_deg: float
    near_focus_m: float
    far_m: float

    def up(self) -> tuple[float, float, float]:
        """The up vector: world +y turned by roll_deg about the view axis (a view along +z assumed)."""
        r = math.radians(self.roll_deg)
        return (round(math.sin(r), 6), round(math.cos(r), 6), 0.0)

    def params(self, fov_deg: float, width: int, height: int, spp: int) -> dict[str, str]:
        """The scene's <default> values for this framing, a horizontal field of `fov_deg` (degrees)."""

        def v(p):
            return ", ".join(f"{c:g}" for c in p)

        return {
            "origin": v(self.origin),
            "target": v(self.target),
            "up": v(self.up()),
            "fov": f"{fov_deg:.6g}",
            "width": str(width),
            "height": str(height),
            "spp": str(spp),
        }


# the doublet (±2°, 9.8 m wide at 140 m): the office blocks closing the street, a car, posts at 20 and 60 m
NARROW = Framing((0.0, 1.4, 0.0), (3.5, 5.0, 140.0), 5.0, 20.0, 140.0)
# a wide lens: the street ahead, buildings, cars, poles and pedestrians on both sides
WIDE = Framing((0.0, 1.4, 0.0), (1.0, 3.0, 40.0), 5.0, 8.0, 140.0)
NARROW_MAX_DEG = 5.0
FRAMINGS = {"solas-doublet": NARROW, "cooke-triplet": WIDE}


def framing(lens) -> Framing:
    """The framing of `lens` (a Lens): its entry in FRAMINGS, else NARROW or WIDE by its half field."""
    return FRAMINGS.get(lens.name, NARROW if lens.field_deg <= NARROW_MAX_DEG else WIDE)
