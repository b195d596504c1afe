"""Fraunhofer PSFs of the lens as built at a field (x, y degrees), from a grid of real rays traced by the Dr.Jit
tracer in local frames (`psf.as_built.Beam`): each ray's optical path to the reference sphere about the chief
ray's image point on the image plane (in that plane's own frame: a tilted sensor's), whose radius is the chief ray's path back to
the paraxial exit-pupil plane (about the nominal axis), and the direction cosines (α, β) of its point on the
sphere seen from the image point. The Fraunhofer integral over the sphere, ∫ A e^{ikW} e^{−ik(αu + βv)} dα dβ
with A² the power per dα dβ, is summed over the rays: each carries √(p dΩ) (its power p and the solid angle
dΩ = |∂(α, β)/∂(ex, ey)| dA its entrance cell maps to, the Jacobian by finite differences of offset traces),
separable in u and v as `fraunhofer.fraunhofer`'s matrix DFT, in the same units (1/µm²; the on-axis entrance
pupil carries power 1). The pupil's rim is the entrance grid's staircase (errors of about one cell's width
over the pupil's radius at the rim; `tests/psf/test_as_built_psf.py` measures them). Lengths in mm.
"""

from __future__ import annotations

import math

import numpy as np

from ..optics.lens import Lens
from ..optics.local_trace import Bundle
from ..optics.paraxial import paraxial
from ..optics.placement import frames
from .as_built import Beam, beams, pupil_density, ray_power, trace_beams
from .base import grid_offsets

STEP = 1e-4  # the finite-difference step of the Jacobian, as a fraction of the pupil square's half-width


def sphere_points(lens: Lens, b: Beam, out: Bundle, wavelength_nm: float, radius: float):
    """(α, β, optical path to the sphere, ok) of the rays `out` of beam `b` traced to the image plane: α, β the
    direction cosines from the chief ray's image point to where each ray crosses the reference sphere of `radius`,
    in the image plane's frame."""
    axes = frames(lens.surfaces, lens.image_placement)[-1][1]
    d = np.stack([out.dx, out.dy, out.dz], axis=1) @ axes  # directions in the image plane's frame
    p0 = np.append(b.chief.image_xy[0], 0.0)
    w = np.stack([out.image_x, out.image_y, np.zeros(len(out.x))], axis=1) - p0
    wd = np.sum(w * d, axis=1)
    t = wd + np.sqrt(wd * wd - np.sum(w * w, axis=1) + radius * radius)  # back along each ray to the sphere
    q = w - t[:, None] * d
    n_image = float(lens.surfaces[-1].glass.index(wavelength_nm))
    return q[:, 0] / radius, q[:, 1] / radius, out.opl - n_image * t, out.ok


def reference_radius(lens: Lens, chief: Bundle, wavelength_nm: float) -> float:
    """The reference sphere's radius (mm): the chief ray's (`chief`, traced) path back to the paraxial exit-pupil
    plane."""
    cd = np.array([chief.dx[0], chief.dy[0], chief.dz[0]]) @ frames(lens.surfaces, lens.image_placement)[-1][1]
    p = paraxial(lens, wavelength_nm)
    return float((p.image_z_mm - p.exit_pupil_z_mm) / cd[2])


def traced_sets(lens: Lens, found: list[Beam], rays: int, wavelength_nm: float) -> list[list[Bundle]]:
    """For each of beams `found`: its rays×rays grid, its chief ray and the grid moved by ±`STEP` of its half-width
    in x, then in y (the Jacobian's offsets), traced: six `Bundle`s per beam, every beam's in one trace."""
    entrance = []
    for b in found:
        ex, ey = b.grid(rays)
        h = STEP * b.half
        chief = tuple(np.array([c]) for c in b.centre)
        entrance += [(ex, ey), chief, (ex + h, ey), (ex - h, ey), (ex, ey + h), (ex, ey - h)]
    traced = trace_beams(lens, [b for b in found for _ in range(6)], entrance, wavelength_nm)
    return [traced[6 * i : 6 * i + 6] for i in range(len(found))]


def fraunhofer(lens: Lens, field_deg, wavelength_nm, pitch_um: float, size: int, rays: int) -> np.ndarray:
    """Fraunhofer PSFs (n, size, size) in 1/µm² of the lens as built at fields `field_deg` (n, 2) and
    `wavelength_nm` (n,, or one), each traced (a grid over the whole field: no half of it mirrored)."""
    field_deg = np.asarray(field_deg, dtype=np.float64).reshape(-1, 2)
    wavelength_nm = np.broadcast_to(np.asarray(wavelength_nm, dtype=np.float64), (len(field_deg),))
    out = np.zeros((len(field_deg), size, size))
    for w in np.unique(wavelength_nm):
        at = np.flatnonzero(wavelength_nm == w)  # the fields of one wavelength aimed and traced together
        found = beams(lens, field_deg[at], float(w))
        for i, b, traced in zip(at, found, traced_sets(lens, found, rays, float(w))):
            out[i] = beam_psf(lens, b, traced, float(w), pitch_um, size, rays)
    return out


def field_psf(lens: Lens, field_deg, wavelength_nm: float, pitch_um: float, size: int, rays: int) -> np.ndarray:
    """The Fraunhofer PSF (size, size) in 1/µm² of the lens as built at `field_deg` (x, y degrees) (`beam_psf`)."""
    return fraunhofer(lens, [field_deg], wavelength_nm, pitch_um, size, rays)[0]


def beam_psf(lens: Lens, b: Beam, traced: list[Bundle], wavelength_nm: float, pitch_um: float, size: int, rays: int):
    """The Fraunhofer PSF (size, size) in 1/µm² of the lens as built across beam `b` (`as_built.beams`: a field's),
    on the image plane's grid about the chief ray's image point (rows down from +y, as `fraunhofer.fraunhofer`),
    from rays×rays rays (`traced`: their `traced_sets`)."""
    ex, ey = b.grid(rays)
    grid, chief, *offsets = traced
    radius = reference_radius(lens, chief, wavelength_nm)
    alpha, beta, path, ok = sphere_points(lens, b, grid, wavelength_nm, radius)
    h = STEP * b.half
    jac = []
    for forward, backward in (offsets[:2], offsets[2:]):  # forward differences, backward where the forward ray is lost
        a1, b1, _, ok1 = sphere_points(lens, b, forward, wavelength_nm, radius)
        a0, b0, _, ok0 = sphere_points(lens, b, backward, wavelength_nm, radius)
        jac.append(np.where(ok1, [a1 - alpha, b1 - beta], [alpha - a0, beta - b0]) / h)
        ok &= ok1 | ok0
    solid = np.abs(jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0]) * (2.0 * b.half / rays) ** 2
    centre = np.flatnonzero(ok)[np.argmin(np.hypot(ex - b.centre[0], ey - b.centre[1])[ok])]
    opd = path - path[centre]  # to the ray nearest the chief ray
    wave = wavelength_nm * 1e-6
    lam = wave / float(lens.surfaces[-1].glass.index(wavelength_nm))  # in image space
    k = 2.0 * math.pi / lam
    amp = np.sqrt(ray_power(pupil_density(lens, wavelength_nm), b, rays) * solid[ok]) * np.exp(
        2j * math.pi * opd[ok] / wave
    )
    offs = grid_offsets(size, pitch_um) * 1e-3
    ku = np.exp(-1j * k * np.outer(alpha[ok], offs))  # (rays, size): columns u = +x
    kv = np.exp(-1j * k * np.outer(beta[ok], -offs))  # rows v = −offsets: down from +y
    field = (kv * amp[:, None]).T @ ku
    return (field.real**2 + field.imag**2) / lam**2 * 1e-6


__all__ = ["STEP", "beam_psf", "field_psf", "reference_radius", "traced_sets", "fraunhofer", "sphere_points"]
