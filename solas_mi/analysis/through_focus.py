"""Through-focus MTF: the diffraction MTF at one frequency as the image plane moves along the axis
(+: away from the lens), tangential and sagittal, at chosen fields; each position's PSF is a new pupil
function about that plane's chief-ray point (no defocus term is added by hand)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..errors import SolasError
from ..metrics.mtf import pixel_mtf
from . import figures, inputs
from . import options as O
from .base import Result, Table
from .mtf import CONVENTIONS, DIRECTIONS, lens_otf


def refocused(lens, shift_mm: float):
    """`lens` with its image plane `shift_mm` further from the last surface (negative: nearer)."""
    last = lens.surfaces[-1]
    if last.thickness + shift_mm < 0:
        raise SolasError(
            f"a focus shift of {shift_mm * 1e3:g} um puts the image plane before lens {lens.name}'s "
            f"last surface ({last.thickness * 1e3:g} um behind it); give a smaller --focus-range-um"
        )
    return replace(lens, surfaces=lens.surfaces[:-1] + (replace(last, thickness=last.thickness + shift_mm),))


@dataclass(frozen=True, kw_only=True)
class ThroughFocus(Result):
    """`mtf` (positions, fields, 2) [tangential, sagittal] at `frequency_cy_mm` for image-plane shifts
    `focus_um` (µm, + away from the lens)."""

    fields_deg: tuple[float, ...]
    frequency_cy_mm: float
    focus_um: np.ndarray
    mtf: np.ndarray

    def best_focus_um(self) -> dict:
        """Per field and direction, the shift (µm) of the largest MTF, refined by a parabola through the
        sample and its neighbours."""
        out = {}
        for i, f in enumerate(self.fields_deg):
            out[f"{f:g}"] = {d: _peak(self.focus_um, self.mtf[:, i, j]) for j, d in enumerate(DIRECTIONS)}
        return out

    def table(self) -> Table:
        rows = tuple(
            (f, float(z), *self.mtf[k, i].tolist())
            for i, f in enumerate(self.fields_deg)
            for k, z in enumerate(self.focus_um)
        )
        return Table(
            ("field_deg", "focus_shift_um", "tangential", "sagittal"), rows, {"best_focus_um": self.best_focus_um()}
        )

    def plot(self):
        fig, (ax,) = figures.figure(self, 1, size=(6.4, 4.2))
        for i, (f, colour) in enumerate(zip(self.fields_deg, figures.colours(len(self.fields_deg)))):
            for j, d in enumerate(DIRECTIONS):
                ax.plot(
                    self.focus_um, self.mtf[:, i, j], color=colour, ls=figures.LINESTYLES[d], label=f"{f:g} deg {d}"
                )
        ax.axvline(0.0, color="black", lw=0.6)
        ax.set(
            xlabel="image plane shift (um, + away from the lens)",
            ylabel=f"MTF at {self.frequency_cy_mm:g} cycles/mm",
            ylim=(0, 1.02),
        )
        ax.grid(alpha=0.3)
        figures.legend(ax, loc="center left", bbox_to_anchor=(1.02, 0.5))
        return fig


def _peak(z: np.ndarray, m: np.ndarray) -> float:
    """The position of the largest `m` over `z`, refined by a parabola through its neighbours."""
    k = int(np.argmax(m))
    if 0 < k < len(m) - 1:
        a, b, c = m[k - 1], m[k], m[k + 1]
        denominator = a - 2 * b + c
        if denominator < 0:
            return float(z[k] + 0.5 * (a - c) / denominator * (z[k + 1] - z[k]))
    return float(z[k])


def through_focus(
    lens,
    frequency_cy_mm=None,
    fields_deg=None,
    wavelengths_nm=None,
    weights=None,
    focus_range_um=None,
    focus_steps: int = O.FOCUS_STEPS,
    pupil_samples: int | None = None,
    pixel_pitch_um=None,
    fill_factor: float = 1.0,
) -> ThroughFocus:
    """Diffraction MTF at `frequency_cy_mm` (default 1/4 of the cut-off) at `focus_steps` image-plane
    shifts across ±`focus_range_um` (default 8 λN²), tangential and sagittal, at `fields_deg`."""
    fields = inputs.fields(lens, fields_deg)
    wl, w8 = inputs.wavelengths(lens, wavelengths_nm, weights)
    if frequency_cy_mm is None:
        freq = round(O.FOCUS_FRACTION * inputs.cutoff_cy_mm(lens, inputs.wavelength(lens, None))) or 1.0
    else:
        freq = inputs.frequencies(lens, [frequency_cy_mm], wl)[0]
    half = inputs.focus_range(lens, focus_range_um)
    steps = inputs.count(focus_steps, "focus steps", 3)
    samples = inputs.pupil_samples(pupil_samples)
    pitch, fill = inputs.pixel(pixel_pitch_um, fill_factor)
    shifts = np.linspace(-half, half, steps)
    lenses = [refocused(lens, z * 1e-3) for z in shifts]  # every position checked before any work
    values, warnings = np.empty((steps, len(fields), 2)), []
    for k, moved in enumerate(lenses):
        otf, w = lens_otf(moved, fields, wl, w8, np.array([freq]), samples)
        values[k], warnings = np.abs(otf[:, :, 0]), warnings or w
    if pitch is not None:
        values *= pixel_mtf(np.array([freq]), pitch, fill)[0]
    return ThroughFocus.of(
        lens,
        "through-focus",
        conventions=CONVENTIONS + ("focus shift: the image plane's move along the axis, + away from the lens, um",),
        warnings=warnings,
        inputs={
            "frequency_cy_mm": float(freq),
            "fields_deg": fields,
            "wavelengths_nm": wl,
            "weights": w8,
            "focus_range_um": half,
            "focus_steps": steps,
            "pupil_samples": samples,
            "pixel_pitch_um": pitch,
            "fill_factor": fill,
        },
        fields_deg=fields,
        frequency_cy_mm=float(freq),
        focus_um=shifts,
        mtf=values,
    )
