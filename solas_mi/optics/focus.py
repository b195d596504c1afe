"""Unit focusing: the whole lens moves relative to the image plane so that an object at a chosen
distance is in focus. The image plane moves by the shift of the paraxial image of the object (primary
wavelength) between the lens file's object distance and the chosen one, so the lens file's own
focus offset (an image plane set inside paraxial focus, say) is kept. Lengths in mm.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import replace

from ..errors import SolasError
from .lens import Lens, check_lens
from .paraxial import paraxial


def focused(lens: Lens, distance_mm: float) -> Lens:
    """`lens` with its object `distance_mm` in front of surface 1 (math.inf: at infinity) and its
    image plane (the last surface's thickness, 0 where it lies on that surface) moved to keep that object in focus."""
    check_lens(lens)
    if (
        not isinstance(distance_mm, numbers.Real)
        or isinstance(distance_mm, bool)
        or math.isnan(distance_mm)
        or not distance_mm > 0
    ):
        raise SolasError(f"focus distance {distance_mm!r} mm must be a positive number (math.inf: at infinity)")
    target = replace(lens, object_distance=float(distance_mm))
    shift = paraxial(target).focus_z_mm - paraxial(lens).focus_z_mm
    last = lens.surfaces[-1]
    thickness = last.thickness + shift
    if not (
        math.isfinite(thickness)
        and thickness >= 0
        and paraxial(target).efl_mm > 0
        and distance_mm > paraxial(target).efl_mm
    ):
        raise SolasError(
            f"lens {lens.name} cannot focus on an object {distance_mm:g} mm in front of surface 1 "
            f"(its real image would lie {thickness:g} mm behind the last surface); allowed: "
            f"distances beyond the focal length {paraxial(lens).efl_mm:.4g} mm"
        )
    return replace(target, surfaces=lens.surfaces[:-1] + (replace(last, thickness=float(thickness)),))
