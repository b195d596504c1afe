"""Image irradiance of a uniform object, from the sequential tracer: the relative illumination
that a render of a white object must reproduce.

For an object at infinity of radiance L, the irradiance at the image of field θ is
E(θ) = L · A(θ) · dω/dA_image, with A(θ) the transmitted cross-section of the collimated beam
(the pupil's transmission × the paraxial entrance-pupil area) and dω/dA_image = cos³θ / J(θ), where
J = |∂(x, y)/∂(tan θx, tan θy)| of the chief ray's image point; `relative_illumination` gives
E(θ)/E(0) in this form. Rays through the rim of a beam map with a slightly different J than its
chief ray (by ≈ u'², 0.4 % for the doublet, and more off axis), so `irradiance` integrates exactly on
the image side instead: E = L ∫ cos θ dω over the directions from the image point that leave
through the lens.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import SolasError
from .lens import Lens
from .paraxial import paraxial

_STEP = 1e-4  # tangent step of the finite differences
_POLAR_STEP_DEG = 0.01  # polar-angle step of the finite differences of lenses with polar fields


def _jacobian(lens: Lens, field_deg: np.ndarray, wavelength_nm: float) -> np.ndarray:
    """|∂(x, y)/∂(tan x, tan y)| (mm²) of the chief ray's image point at each field (n, 2)."""
    from .pupil import chief_rays

    tan = np.tan(np.radians(field_deg))
    steps = np.array([[_STEP, 0.0], [-_STEP, 0.0], [0.0, _STEP], [0.0, -_STEP]])
    shifted = (tan[:, None, :] + steps[None]).reshape(-1, 2)
    xy = chief_rays(lens, np.degrees(np.arctan(shifted)), np.full(len(shifted), wavelength_nm)).image_xy
    xy = xy.reshape(-1, 4, 2)
    dx = (xy[:, 0] - xy[:, 1]) / (2 * _STEP)
    dy = (xy[:, 2] - xy[:, 3]) / (2 * _STEP)
    return np.abs(dx[:, 0] * dy[:, 1] - dx[:, 1] * dy[:, 0])


def irradiance(lens: Lens, image_xy: np.ndarray, wavelength_nm: float, samples: int = 512) -> np.ndarray:
    """E / L (steradians) of a lossless lens at image points (n, 2) in mm: ∫ cos θ dω over the rays
    from each point that pass every aperture, on a samples² grid over the last surface's vertex plane
    (the lens traced backwards)."""
    from .exit_pupil import passes, reversed_lens

    if not lens.at_infinity:
        raise SolasError("image irradiance is defined here for objects at infinity only")
    rev = reversed_lens(lens)
    reach = 1.05 * lens.surfaces[-1].semi_diameter
    step = 2.0 * reach / samples
    g = -reach + (np.arange(samples) + 0.5) * step
    ex, ey = (a.ravel() for a in np.meshgrid(g, g))
    dz = lens.surfaces[-1].thickness
    out = []
    for x, y in np.atleast_2d(np.asarray(image_xy, dtype=np.float64)):
        ok = passes(rev, x, y, ex, ey, wavelength_nm)
        cos2 = dz * dz / ((ex - x) ** 2 + (ey - y) ** 2 + dz * dz)
        out.append(np.sum((cos2 * cos2)[ok]) * step * step / (dz * dz))
    return np.array(out)


def axis_irradiance(lens: Lens, wavelength_nm: float) -> float:
    """E / L on the axis of a lossless lens (steradians)."""
    return float(irradiance(lens, np.zeros((1, 2)), wavelength_nm, samples=1024)[0])


def ideal_irradiance(lens: Lens, focal_mm: float, wavelength_nm: float | None = None) -> float:
    """E / L (steradians) of the ideal camera (`camera`): the lens's paraxial entrance pupil area over
    the pinhole focal length squared. Renders and convolutions report irradiance in this unit, so an
    ideal lossless lens returns the input radiance."""
    r_ep = 0.5 * paraxial(lens, wavelength_nm).entrance_pupil_diameter_mm
    return math.pi * r_ep ** 2 / focal_mm ** 2


def relative_illumination(lens: Lens, field_deg: np.ndarray, wavelength_nm: float, pupil_samples: int = 128
                          ) -> np.ndarray:
    """E(θ)/E(0) at fields (n, 2) in degrees: transmission × cos³θ × J(0)/J(θ), relative to the
    transmission on the axis."""
    from .pupil import pupil_function

    field_deg = np.atleast_2d(np.asarray(field_deg, dtype=np.float64))
    lens.check_wavelength(wavelength_nm)
    fields = np.vstack([np.zeros((1, 2)), field_deg])
    transmission = pupil_function(lens, fields, np.full(len(fields), wavelength_nm), pupil_samples).transmission
    if lens.field_type.sideways:  # fields to 90° and beyond: per solid angle, sinθ dθ dφ onto h dh dφ
        scale = _polar_scale(lens, fields, wavelength_nm)
        return transmission[1:] / transmission[0] * scale[0] / scale[1:]
    tan = np.tan(np.radians(field_deg))
    cos3 = (1.0 + (tan ** 2).sum(axis=1)) ** -1.5
    j = _jacobian(lens, fields, wavelength_nm)
    return transmission[1:] / transmission[0] * cos3 * j[0] / j[1:]


def _polar_scale(lens: Lens, field_deg: np.ndarray, wavelength_nm: float) -> np.ndarray:
    """Image area per unit solid angle, h·(dh/dθ)/sin θ (mm²/sr; (dh/dθ)² on the axis), at polar fields
    (n, 2) of a rotationally symmetric lens: h the chief ray's image height, dh/dθ from a second chief
    ray _POLAR_STEP_DEG nearer the axis (the edge of the field has nothing beyond it)."""
    from .pupil import chief_rays

    theta = np.radians(np.hypot(field_deg[:, 0], field_deg[:, 1]))
    step = np.radians(_POLAR_STEP_DEG)
    other = np.where(theta > 0, np.maximum(theta - step, 0.0), step)
    azimuth = np.arctan2(field_deg[:, 1], field_deg[:, 0])
    direction = np.stack([np.cos(azimuth), np.sin(azimuth)], -1)
    both = np.degrees(np.concatenate([theta, other]))[:, None] * np.vstack([direction, direction])
    h = np.hypot(*chief_rays(lens, both, np.full(len(both), wavelength_nm)).image_xy.T)
    h, h_other = h[:len(theta)], h[len(theta):]
    slope = (h - h_other) / (theta - other)
    return np.where(theta > 0, h * slope / np.maximum(np.sin(theta), 1e-300), slope ** 2)


def image_scales(lens: Lens, max_height_mm: float, wavelength_nm: float, samples: int = 64):
    """Radial and tangential image scales of the chief ray (mm per unit field tangent) at image
    heights 0…max_height_mm: (heights, dh/dt, h/t). Their reciprocals turn a length on the image plane
    into a width in field tangent (a pixel's footprint on the object)."""
    from .pupil import chief_rays

    f0 = math.sqrt(float(_jacobian(lens, np.zeros((1, 2)), wavelength_nm)[0]))
    t_max = 1.05 * max_height_mm / f0  # past the farthest height, distortion being small
    t = np.linspace(0.0, t_max, samples)
    tt = np.concatenate([t, t + _STEP])
    h = chief_rays(lens, np.stack([np.degrees(np.arctan(tt)), np.zeros_like(tt)], -1),
                   np.full(len(tt), wavelength_nm)).image_xy[:, 0]
    radial = (h[samples:] - h[:samples]) / _STEP
    tangential = np.concatenate([[radial[0]], h[1:samples] / t[1:]])
    return h[:samples], radial, tangential
