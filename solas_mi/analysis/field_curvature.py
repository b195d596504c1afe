"""Field curvature and astigmatism: where the rays beside each field's chief ray come to a focus, in the
tangential plane (a pair at normalised pupil y = ±ε) and the sagittal plane (x = ±ε), measured along
the axis from the image plane (+: away from the lens). As ε → 0 these are the Coddington foci of the
chief ray; ε = 1e-4 leaves an error of order ε² of the pupil's aberrations (nm)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..optics.paraxial import paraxial
from . import figures, inputs
from . import options as O
from .base import Result, Table, defined
from .rays import pupil_rays

EPSILON = 1e-4  # normalised pupil offset of the ray pairs
CONVENTIONS = (
    "focus: where a pair of rays at normalised pupil +-1e-4 beside the chief ray (y: tangential, x: sagittal; "
    "fields on +y) cross, along the axis from the image plane, mm, + away from the lens",
    "astigmatism: tangential focus - sagittal focus, mm",
    "normalised pupil coordinates: points of the stop (real ray aiming), 1 at its rim",
)


@dataclass(frozen=True, kw_only=True)
class FieldCurvature(Result):
    """`tangential_mm`, `sagittal_mm` (wavelengths, fields): focus positions from the image plane;
    `paraxial_focus_mm`: the paraxial focus from the image plane at the primary wavelength."""

    fields_deg: tuple[float, ...]
    wavelengths_nm: tuple[float, ...]
    tangential_mm: np.ndarray
    sagittal_mm: np.ndarray
    paraxial_focus_mm: float

    def table(self) -> Table:
        rows = tuple(
            (f, w, defined(t), defined(s), defined(t - s))
            for j, w in enumerate(self.wavelengths_nm)
            for i, f in enumerate(self.fields_deg)
            for t, s in [(self.tangential_mm[j, i], self.sagittal_mm[j, i])]
        )
        return Table(
            ("field_deg", "wavelength_nm", "tangential_focus_mm", "sagittal_focus_mm", "astigmatism_mm"),
            rows,
            {"paraxial_focus_mm": self.paraxial_focus_mm},
        )

    def plot(self):
        fig, (left, right) = figures.figure(self, 2, size=(4.4, 4.0))
        for j, w in enumerate(self.wavelengths_nm):
            colour = figures.wavelength_colour(w)
            left.plot(self.tangential_mm[j], self.fields_deg, color=colour, label=f"{w:g} nm tangential")
            left.plot(self.sagittal_mm[j], self.fields_deg, color=colour, ls="--", label=f"{w:g} nm sagittal")
            right.plot(self.tangential_mm[j] - self.sagittal_mm[j], self.fields_deg, color=colour, label=f"{w:g} nm")
        left.axvline(0.0, color="black", lw=0.6)
        left.axvline(self.paraxial_focus_mm, color="grey", ls=":", label="paraxial focus")
        left.set(
            title="field curvature",
            xlabel="focus from the image plane (mm)",
            ylabel="field (deg)",
            ylim=(0, self.fields_deg[-1]),
        )
        right.axvline(0.0, color="black", lw=0.6)
        right.set(
            title="astigmatism",
            xlabel="tangential - sagittal focus (mm)",
            ylabel="field (deg)",
            ylim=(0, self.fields_deg[-1]),
        )
        for ax in (left, right):
            ax.grid(alpha=0.3)
            figures.legend(ax)
        return fig


def field_curvature(lens, field_samples: int = O.FIELD_SAMPLES, wavelengths_nm=None) -> FieldCurvature:
    """Tangential and sagittal focus (mm from the image plane) against field, 0 … the half field, at each
    wavelength (default the lens file's)."""
    fields = inputs.field_range(lens, field_samples)
    wl, _ = inputs.wavelengths(lens, wavelengths_nm)
    pairs_f = np.repeat(fields, len(wl))
    pairs_w = np.tile(wl, len(fields))
    px = np.array([0.0, 0.0, EPSILON, -EPSILON])
    py = np.array([EPSILON, -EPSILON, 0.0, 0.0])
    rays = pupil_rays(lens, pairs_f, pairs_w, px, py)
    dx, dy, dz = rays.direction
    mx, my = dx / dz, dy / dz
    tangential = -(rays.y_mm[:, 0] - rays.y_mm[:, 1]) / (my[:, 0] - my[:, 1])
    sagittal = -(rays.x_mm[:, 2] - rays.x_mm[:, 3]) / (mx[:, 2] - mx[:, 3])
    shape = (len(fields), len(wl))
    p = paraxial(lens)
    return FieldCurvature.of(
        lens,
        "field-curvature",
        conventions=CONVENTIONS,
        inputs={"fields_deg": fields, "wavelengths_nm": wl},
        fields_deg=fields,
        wavelengths_nm=wl,
        tangential_mm=tangential.reshape(shape).T,
        sagittal_mm=sagittal.reshape(shape).T,
        paraxial_focus_mm=p.focus_z_mm - p.image_z_mm,
    )
