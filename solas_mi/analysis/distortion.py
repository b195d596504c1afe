"""Distortion against field: the real chief ray's image height h(θ) against three references, each in
percent, (h − h_ref)/h_ref × 100:

- f tan θ: h_ref = m tan θ, m the paraxial chief ray's image height per unit tan θ on the image plane
  (the EFL where the image plane is at paraxial focus; the near-axis limit of the real chief ray, as
  Zemax and optiland take it), undefined from 90°;
- f θ: h_ref = m θ, the same m (equidistant, the fisheye's reference);
- the closest projection (`optics.distortion.fit_projections`: rectilinear, equidistant, equisolid,
  stereographic, each with its own least-squares focal length): the residual against it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..optics.distortion import PROJECTIONS, closest_projection, fit_projections
from ..optics.paraxial import paraxial
from ..optics.pupil import chief_rays
from . import figures, inputs
from . import options as O
from .base import Result, Table, defined

REFERENCE_DEG = 1.0  # the field whose paraxial chief ray gives m (paraxial heights are linear in tan θ)
CONVENTIONS = (
    "distortion % = (h - h_ref) / h_ref x 100, h the real chief ray's image height (fields on +y, mm)",
    "f-tan: h_ref = m tan(theta); f-theta: h_ref = m theta; m the paraxial chief ray's height per unit tan(theta) "
    "on the image plane (the EFL when the image plane is at paraxial focus)",
    "closest projection: the one of rectilinear, equidistant, equisolid, stereographic whose least-squares focal "
    "length fits h(theta) best; its column: h against that fit",
)


@dataclass(frozen=True, kw_only=True)
class Distortion(Result):
    """Per field (`fields_deg`): `height_mm` (real chief ray) and the percent distortion against f tan θ
    (NaN from 90°), f θ and the closest projection `projection` of focal length `projection_focal_mm`."""

    fields_deg: tuple[float, ...]
    wavelength_nm: float
    height_mm: np.ndarray
    scale_mm: float
    f_tan_percent: np.ndarray
    f_theta_percent: np.ndarray
    projection: str
    projection_focal_mm: float
    projection_percent: np.ndarray

    def table(self) -> Table:
        rows = tuple(
            (f, float(h), defined(a), defined(b), defined(c))
            for f, h, a, b, c in zip(
                self.fields_deg, self.height_mm, self.f_tan_percent, self.f_theta_percent, self.projection_percent
            )
        )
        return Table(
            ("field_deg", "image_height_mm", "f_tan_percent", "f_theta_percent", "projection_percent"),
            rows,
            {"scale_mm": self.scale_mm, "projection": self.projection, "projection_focal_mm": self.projection_focal_mm},
        )

    def plot(self):
        fig, axes = figures.figure(self, 3, columns=3, size=(3.6, 3.8))
        for ax, values, title in (
            (axes[0], self.f_tan_percent, f"against f tan(theta), f = {self.scale_mm:.4g} mm"),
            (axes[1], self.f_theta_percent, f"against f theta, f = {self.scale_mm:.4g} mm"),
            (axes[2], self.projection_percent, f"against {self.projection}, f = {self.projection_focal_mm:.4g} mm"),
        ):
            if np.isfinite(values).any():
                ax.plot(values, self.fields_deg, marker=".")
            ax.axvline(0.0, color="black", lw=0.6)
            ax.set(
                xlabel=f"distortion at {self.wavelength_nm:g} nm (%)",
                ylabel="field (deg)",
                ylim=(0, self.fields_deg[-1]),
                title=title,
            )
            ax.title.set_fontsize("medium")
            ax.grid(alpha=0.3)
        return fig


def _percent(h: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """(h − ref)/ref × 100; 0 on the axis (ref 0), NaN where ref is undefined (NaN)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(reference == 0, 0.0, (h - reference) / reference * 100.0)


def distortion(lens, field_samples: int = O.FIELD_SAMPLES, wavelength_nm=None) -> Distortion:
    """Distortion against field (0 … the half field) at `wavelength_nm` (default the primary)."""
    fields = np.array(inputs.field_range(lens, field_samples))
    wl = inputs.wavelength(lens, wavelength_nm)
    chief = chief_rays(lens, np.stack([np.zeros_like(fields), fields], axis=-1), np.full(len(fields), wl))
    h = chief.image_xy[:, 1]
    m = paraxial(lens, wl, [REFERENCE_DEG]).chief_ray_image_height_mm[0] / math.tan(math.radians(REFERENCE_DEG))
    theta = np.radians(fields)
    f_tan = np.where(fields < 90.0, m * np.tan(np.minimum(theta, np.radians(89.9))), np.nan)
    fits = fit_projections(fields, h)
    name = closest_projection(fits)
    focal = fits[name][0]
    return Distortion.of(
        lens,
        "distortion",
        conventions=CONVENTIONS,
        inputs={"fields_deg": tuple(fields.tolist()), "wavelength_nm": wl},
        fields_deg=tuple(fields.tolist()),
        wavelength_nm=wl,
        height_mm=h,
        scale_mm=float(m),
        f_tan_percent=_percent(h, f_tan),
        f_theta_percent=_percent(h, m * theta),
        projection=name,
        projection_focal_mm=float(focal),
        projection_percent=_percent(h, focal * PROJECTIONS[name](theta)),
    )
