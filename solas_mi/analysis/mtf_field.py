"""The diffraction MTF against field: at chosen frequencies (`mtf_field`), and the frequency where it
falls to one half (`mtf50_field`), tangential and sagittal, from 0 to the lens's half field, optionally
times the pixel's MTF (then MTF50 also in cycles/pixel, the unit of image measurements)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..metrics.mtf import mtf50, pixel_mtf
from . import figures, inputs
from . import options as O
from .base import Result, Table, defined
from .mtf import CONVENTIONS, DIRECTIONS, lens_otf

MTF50_SAMPLES = 401  # frequencies from 0 to the cut-off where MTF50 is looked for


def _common(lens, field_samples, wavelengths_nm, weights, pupil_samples, pixel_pitch_um, fill_factor):
    """The checked inputs every MTF-against-field analysis shares, and their record (`Result.inputs`)."""
    fields = inputs.field_range(lens, field_samples)
    wl, w8 = inputs.wavelengths(lens, wavelengths_nm, weights)
    samples = inputs.pupil_samples(pupil_samples)
    pitch, fill = inputs.pixel(pixel_pitch_um, fill_factor)
    record = {
        "fields_deg": fields,
        "wavelengths_nm": wl,
        "weights": w8,
        "pupil_samples": samples,
        "pixel_pitch_um": pitch,
        "fill_factor": fill,
    }
    return fields, wl, w8, samples, pitch, fill, record


@dataclass(frozen=True, kw_only=True)
class MTFField(Result):
    """`mtf` (fields, 2, K) [tangential, sagittal] at `frequencies_cy_mm` (K,) for `fields_deg`;
    including the pixel's MTF where `pixel` (K,) is not None."""

    fields_deg: tuple[float, ...]
    frequencies_cy_mm: tuple[float, ...]
    mtf: np.ndarray
    pixel: np.ndarray | None

    def table(self) -> Table:
        rows = tuple(
            (f, nu, *self.mtf[i, :, k].tolist())
            for k, nu in enumerate(self.frequencies_cy_mm)
            for i, f in enumerate(self.fields_deg)
        )
        return Table(("field_deg", "frequency_cy_mm", "tangential", "sagittal"), rows)

    def plot(self):
        fig, (ax,) = figures.figure(self, 1, size=(6.4, 4.2))
        for k, (nu, colour) in enumerate(zip(self.frequencies_cy_mm, figures.colours(len(self.frequencies_cy_mm)))):
            for j, d in enumerate(DIRECTIONS):
                ax.plot(
                    self.fields_deg,
                    self.mtf[:, j, k],
                    color=colour,
                    ls=figures.LINESTYLES[d],
                    marker=".",
                    label=f"{nu:g} cy/mm {d}",
                )
        what = "diffraction MTF" + (" x pixel MTF" if self.pixel is not None else "")
        ax.set(xlabel="field (deg)", ylabel=what, ylim=(0, 1.02), xlim=(0, self.fields_deg[-1]))
        ax.grid(alpha=0.3)
        figures.legend(ax, loc="center left", bbox_to_anchor=(1.02, 0.5))
        return fig


def mtf_field(
    lens,
    frequencies_cy_mm=None,
    field_samples: int = O.FIELD_SAMPLES,
    wavelengths_nm=None,
    weights=None,
    pupil_samples: int | None = None,
    pixel_pitch_um=None,
    fill_factor: float = 1.0,
) -> MTFField:
    """Diffraction MTF at `frequencies_cy_mm` against field (`field_samples` from 0 to the half field),
    tangential and sagittal."""
    fields, wl, w8, samples, pitch, fill, record = _common(
        lens, field_samples, wavelengths_nm, weights, pupil_samples, pixel_pitch_um, fill_factor
    )
    freq = inputs.frequencies(lens, frequencies_cy_mm, wl)
    otf, warnings = lens_otf(lens, fields, wl, w8, np.array(freq), samples)
    pixel = None if pitch is None else pixel_mtf(np.array(freq), pitch, fill)
    values = np.abs(otf) * (1.0 if pixel is None else pixel)
    return MTFField.of(
        lens,
        "mtf-field",
        conventions=CONVENTIONS,
        warnings=warnings,
        inputs={"frequencies_cy_mm": freq, **record},
        fields_deg=fields,
        frequencies_cy_mm=freq,
        mtf=values,
        pixel=pixel,
    )


@dataclass(frozen=True, kw_only=True)
class MTF50Field(Result):
    """`mtf50_cy_mm` (fields, 2) [tangential, sagittal], NaN where the MTF never falls to 1/2 below the
    cut-off; `pixel_pitch_um` None or the pixels' pitch (the MTF then includes theirs)."""

    fields_deg: tuple[float, ...]
    mtf50_cy_mm: np.ndarray
    pixel_pitch_um: float | None

    def table(self) -> Table:
        columns = ["field_deg", "tangential_cy_mm", "sagittal_cy_mm"]
        if self.pixel_pitch_um is not None:
            columns += ["tangential_cy_px", "sagittal_cy_px"]
        rows = []
        for f, values in zip(self.fields_deg, self.mtf50_cy_mm):
            row = [f, *(defined(v) for v in values)]
            if self.pixel_pitch_um is not None:
                row += [defined(v * self.pixel_pitch_um * 1e-3) for v in values]
            rows.append(tuple(row))
        return Table(tuple(columns), tuple(rows))

    def plot(self):
        fig, (ax,) = figures.figure(self, 1, size=(6.0, 4.0))
        for j, d in enumerate(DIRECTIONS):
            ax.plot(self.fields_deg, self.mtf50_cy_mm[:, j], color="C0", ls=figures.LINESTYLES[d], marker=".", label=d)
        with_pixel = "" if self.pixel_pitch_um is None else f" (with {self.pixel_pitch_um:g} um pixels)"
        ax.set(xlabel="field (deg)", ylabel=f"MTF50 (cycles/mm){with_pixel}", xlim=(0, self.fields_deg[-1]))
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        figures.legend(ax)
        return fig


def mtf50_field(
    lens,
    field_samples: int = O.FIELD_SAMPLES,
    wavelengths_nm=None,
    weights=None,
    pupil_samples: int | None = None,
    pixel_pitch_um=None,
    fill_factor: float = 1.0,
) -> MTF50Field:
    """MTF50 (cycles/mm; with `pixel_pitch_um` also cycles/pixel) of the diffraction MTF against field,
    tangential and sagittal."""
    fields, wl, w8, samples, pitch, fill, record = _common(
        lens, field_samples, wavelengths_nm, weights, pupil_samples, pixel_pitch_um, fill_factor
    )
    freq = np.linspace(0.0, inputs.cutoff_cy_mm(lens, min(wl)), MTF50_SAMPLES)
    otf, warnings = lens_otf(lens, fields, wl, w8, freq, samples)
    values = np.abs(otf) * (1.0 if pitch is None else pixel_mtf(freq, pitch, fill))
    found = np.array([[mtf50(values[i, j], freq) for j in range(2)] for i in range(len(fields))], dtype=float)
    return MTF50Field.of(
        lens,
        "mtf50-field",
        conventions=CONVENTIONS,
        warnings=warnings,
        inputs=record,
        fields_deg=fields,
        mtf50_cy_mm=found,
        pixel_pitch_um=pitch,
    )
