"""A lens scaled in size: every length times one factor s (radii, thicknesses, clear diameters, the
object distance, the image circle; the even asphere's A_2i by s^(1−2i) and Forbes' Qbfs terms and
normalisation radius by s, so each sag scales by s), glasses and angles unchanged.

Paraxial laws that follow (W. J. Smith, "Modern Optical Engineering", ch. 2): EFL, back focus and
pupil diameters scale by s, the f-number and the field of view do not; geometric aberrations (spot
sizes, in mm) scale by s, the same in angle; the diffraction pattern (λ·N) does not scale in mm. So a
frame camera with a focal length of F pixels of p µm takes the lens scaled to EFL = F·p: its geometric
blur in pixels is the unscaled lens's on pixels of EFL/F, its diffraction blur λN/p pixels.
"""

from __future__ import annotations

import math
from dataclasses import replace

from ..errors import SolasError
from .lens import Lens
from .surface import Surface


def scaled(lens: Lens, factor: float) -> Lens:
    """`lens` with every length times `factor` (> 0), named "<name> x<factor>"."""
    if not (isinstance(factor, (int, float)) and math.isfinite(factor) and factor > 0):
        raise SolasError(f"lens scale factor {factor!r} must be a positive number")
    s = float(factor)
    return replace(
        lens,
        name=f"{lens.name} x{s:.6g}",
        surfaces=tuple(_surface(x, s) for x in lens.surfaces),
        object_distance=lens.object_distance * s,
        image_diameter=lens.image_diameter * s,
        image_placement=None if lens.image_placement is None else lens.image_placement.scaled(s),
    )


def _surface(surface: Surface, s: float) -> Surface:
    return replace(
        surface,
        radius=surface.radius * s,
        thickness=surface.thickness * s,
        diameter=surface.diameter * s,
        aspheric=tuple(a * s ** (1 - 2 * (i + 2)) for i, a in enumerate(surface.aspheric)),
        qbfs=tuple(a * s for a in surface.qbfs),
        norm_radius=surface.norm_radius * s,
        focal_length=None if surface.focal_length is None else surface.focal_length * s,
        form=None if surface.form is None else surface.form.scaled(s),
        placement=None if surface.placement is None else surface.placement.scaled(s),
    )


def image_scale_mm(lens: Lens) -> float:
    """The paraxial image scale on the lens's image plane (mm per unit tangent of the field): the EFL when
    the image plane is at the paraxial focus (the doublet's lies 0.46 mm inside it: 98.80 against 99.95)."""
    from .paraxial import paraxial

    theta = 1e-3
    return abs(paraxial(lens, fields_deg=[math.degrees(theta)]).chief_ray_image_height_mm[0]) / math.tan(theta)


def scaled_to_focal(lens: Lens, focal_px: float, pixel_um: float, field_deg: float | None = None) -> tuple[Lens, dict]:
    """`lens` scaled so that its focal length is a camera's of `focal_px` pixels of `pixel_um` µm, and what was
    done (for metadata). The lens's focal length: with `field_deg`, the pinhole focal length the convolution
    takes (`camera.pinhole_focal_mm`: the real chief ray of that field), so a grid over that field puts the
    camera's pixels on the sensor exactly; else the paraxial image scale (`image_scale_mm`)."""
    from .camera import pinhole_focal_mm
    from .paraxial import paraxial

    for name, v in (("focal length", focal_px), ("pixel pitch", pixel_um)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise SolasError(f"the camera's {name} {v!r} must be a positive number")
    focal = (lambda x: pinhole_focal_mm(x, field_deg)) if field_deg else image_scale_mm
    factor = focal_px * pixel_um * 1e-3 / focal(lens)
    out = scaled(lens, factor)
    before, after = paraxial(lens), paraxial(out)
    return out, {
        "lens": lens.name,
        "lens_hash": lens.hash,
        "factor": factor,
        "efl_mm": [before.efl_mm, after.efl_mm],
        "f_number": [before.f_number, after.f_number],
        "focal_mm": [focal(lens), focal(out)],
        "camera_focal_px": float(focal_px),
        "pixel_um": float(pixel_um),
        "why": "lens scaled so that its focal length is the camera's (pixels x pixel pitch): "
        + (
            f"the pinhole focal length meeting the real chief ray at {field_deg:g} deg, as the convolution takes it"
            if field_deg
            else "the paraxial image scale on its image plane"
        )
        + "; f-number and field unchanged",
    }
