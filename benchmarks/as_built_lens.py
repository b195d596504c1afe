"""The Cooke triplet as built, the lens as built that the benchmarks time and compare (`bench_psf_grid`,
`asbuilt_optiland`): its middle element decentred by (0.1, −0.05) mm and tilted by (0.4°, −0.3°) (a
coordinate break before it, its reverse after it), with `toroid` its last surface a toroid (its radius,
rotated at 1.002 times it: astigmatism of ~40 µm). The tests' fixture `cooke_as_built` takes it (with a sensor tilt).
"""

from __future__ import annotations

from dataclasses import replace

from solas_mi import Lens
from solas_mi.optics.placement import Placement
from solas_mi.optics.shapes.toroid import Toroid


def cooke_as_built(toroid: bool = True) -> Lens:
    """The Cooke triplet with its middle element decentred and tilted, and with `toroid` a toroid last."""
    base = Lens.load("cooke-triplet")
    surfaces = list(base.surfaces)
    surfaces[2] = replace(surfaces[2], placement=Placement(0.1, -0.05, 0.4, -0.3, 0.0, 0))
    surfaces[4] = replace(surfaces[4], placement=Placement(-0.1, 0.05, -0.4, 0.3, 0.0, 1))
    if toroid:
        last = surfaces[-1]
        surfaces[-1] = replace(last, radius=0.0, form=Toroid(last.radius, 0.0, (), 1.002 * last.radius))
    return replace(base, name="cooke-triplet-as-built", surfaces=tuple(surfaces))
