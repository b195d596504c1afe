"""Two analyses against field at each wavelength, from the chief rays and the image irradiance: lateral
colour (each wavelength's chief-ray image height minus the primary wavelength's, beside the Airy
radius) and relative illumination (`optics.illumination.relative_illumination`: the image irradiance
of a uniform scene at each field's chief-ray point over that on the axis)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..optics.illumination import relative_illumination as illumination
from ..optics.paraxial import paraxial
from ..optics.pupil import chief_rays
from . import figures, inputs
from . import options as O
from .base import Result, Table

CONVENTIONS = ("fields on +y (degrees); heights on the image plane (y)",)


@dataclass(frozen=True, kw_only=True)
class AgainstField(Result):
    """`values` (wavelengths, fields) of one quantity against field at each wavelength; `column`: its
    table column (name with its unit), `label`: the plot's axis label; `reference`: a curve (fields,)
    drawn beside (the Airy radius of lateral colour) or None."""

    fields_deg: tuple[float, ...]
    wavelengths_nm: tuple[float, ...]
    values: np.ndarray
    column: str
    label: str
    reference: np.ndarray | None = None
    reference_label: str = ""

    def table(self) -> Table:
        rows = tuple(
            (f, w, float(self.values[j, i]))
            for j, w in enumerate(self.wavelengths_nm)
            for i, f in enumerate(self.fields_deg)
        )
        return Table(("field_deg", "wavelength_nm", self.column), rows)

    def plot(self):
        fig, (ax,) = figures.figure(self, 1, size=(6.0, 4.0))
        for j, w in enumerate(self.wavelengths_nm):
            ax.plot(self.fields_deg, self.values[j], color=figures.wavelength_colour(w), marker=".", label=f"{w:g} nm")
        if self.reference is not None:
            for sign in (1, -1):
                ax.plot(
                    self.fields_deg,
                    sign * self.reference,
                    color="black",
                    ls=":",
                    lw=0.8,
                    label=self.reference_label if sign > 0 else None,
                )
        ax.set(xlabel="field (deg)", ylabel=self.label, xlim=(0, self.fields_deg[-1]))
        ax.grid(alpha=0.3)
        figures.legend(ax)
        return fig


def lateral_colour(lens, field_samples: int = O.FIELD_SAMPLES, wavelengths_nm=None) -> AgainstField:
    """Chief-ray image height at each wavelength minus the primary's (µm) against field."""
    fields = inputs.field_range(lens, field_samples)
    wl, _ = inputs.wavelengths(lens, wavelengths_nm)
    primary = inputs.wavelength(lens, None)
    every = (*wl, primary)
    pairs = np.array([[0.0, f] for w in every for f in fields])
    heights = chief_rays(lens, pairs, np.repeat(every, len(fields))).image_xy[:, 1].reshape(len(every), len(fields))
    airy = 1.22 * primary * 1e-3 * paraxial(lens, primary).working_f_number  # µm
    return AgainstField.of(
        lens,
        "lateral-colour",
        conventions=CONVENTIONS
        + (
            f"lateral colour: chief-ray image height minus that at the primary "
            f"wavelength {primary:g} nm, um; the Airy radius 1.22 lambda N at "
            f"{primary:g} nm beside it",
        ),
        inputs={"fields_deg": fields, "wavelengths_nm": wl, "primary_nm": primary},
        fields_deg=fields,
        wavelengths_nm=wl,
        values=(heights[:-1] - heights[-1]) * 1e3,
        column="lateral_colour_um",
        label=f"chief-ray height - at {primary:g} nm (um)",
        reference=np.full(len(fields), airy),
        reference_label="Airy radius",
    )


def relative_illumination(lens, field_samples: int = O.FIELD_SAMPLES, wavelengths_nm=None) -> AgainstField:
    """E(θ)/E(0) against field at each wavelength."""
    fields = inputs.field_range(lens, field_samples)
    wl, _ = inputs.wavelengths(lens, wavelengths_nm)
    pairs = np.array([[0.0, f] for f in fields])
    values = np.array([illumination(lens, pairs, w) for w in wl])
    return AgainstField.of(
        lens,
        "relative-illumination",
        conventions=CONVENTIONS
        + (
            "relative illumination: image irradiance of a uniform (Lambertian) "
            "scene at the chief ray's image point over that on the axis",
        ),
        inputs={"fields_deg": fields, "wavelengths_nm": wl},
        fields_deg=fields,
        wavelengths_nm=wl,
        values=values,
        column="relative_illumination",
        label="relative illumination E/E(0)",
    )
