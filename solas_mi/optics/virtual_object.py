"""A virtual object: a negative `object_distance`, the object point that far behind surface 1 (Zemax's
`DISZ` < 0 on `SURF 0`, e.g. the exit pupil of a relay before it). Light arrives converging toward that
point: each ray is the line through the object point and its entrance point, traced from surface 1
(`tracer.launch`, its optical path counted toward the point); the paraxial trace takes the negative
distance as it is. A renderer needs a scene in front of the lens, which cannot hold such a point: the
lens camera (without a focus distance) and the mesh scene refuse it (`check_real`).
"""

from __future__ import annotations

from ..errors import SolasError


def metadata(lens) -> dict:
    """{"virtual_object": where it lies and how it is traced} for a virtual object (`lens info`, PSF
    metadata), {} otherwise."""
    if not lens.virtual_object:
        return {}
    return {
        "virtual_object": f"{-lens.object_distance:g} mm behind surface 1, light converging toward it: each "
        "ray is the line through the object point and its pupil point, traced from surface 1"
    }


def check_real(lens, user: str, instead: str = "trace it instead (lens info, psf)") -> None:
    """SolasError naming `user` (a renderer) when `lens`'s object is virtual; `instead` says what to do."""
    if lens.virtual_object:
        raise SolasError(
            f"{user}: lens {lens.name} has a virtual object, {-lens.object_distance:g} mm behind "
            "surface 1 (light arrives converging toward it), which no scene in front of the lens "
            f"can hold; {instead}"
        )


__all__ = ["metadata", "check_real"]
