"""MTF against spatial frequency at chosen fields: the diffraction MTF from the pupil function's
autocorrelation (`otf`), the geometric MTF from the ray spot, tangential and sagittal, weighted over
wavelengths, optionally times the pixel's MTF (`metrics.mtf.pixel_mtf`); `lens_otf`, the OTFs every
MTF analysis (`mtf_field`, `through_focus`) is made of.

Directions: fields lie on +y, so the tangential MTF is the OTF along y (the frequency varies along the
field's radius: bars perpendicular to it), the sagittal along x. Frequencies in cycles/mm on the image
plane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..metrics.mtf import mtf50, pixel_mtf
from ..optics.pupil import chief_rays, pupil_function
from ..psf.fraunhofer import sampling_need
from ..psf.geometric import entrance_grid_hits
from . import figures, inputs
from . import options as O
from .base import Result, Table
from .otf import AXES, at_frequencies, combine, pupil_line_otf, spot_otf

CHUNK = 12  # field/wavelength pairs whose pupil functions are held at once
# largest phase step a pupil cell may hold: π/4 leaves 8 OTF samples a ripple of a wide PSF's OTF (the grid
# of shifts is the OTF's sampling; at π/2, 4 a ripple, the cubic left 3e-3 on 40 waves of defocus)
STEP = np.pi / 4
DIRECTIONS = tuple(AXES)  # ("tangential", "sagittal")
CONVENTIONS = (
    "fields on +y (degrees); tangential: the OTF along y, the field's radial direction (bars perpendicular to "
    "it); sagittal: along x",
    "frequencies in cycles/mm on the image plane; MTF = |OTF|, 1 at zero frequency",
    "diffraction MTF: autocorrelation of the pupil function on the exit pupil's reference sphere, centred on "
    "each wavelength's chief ray; geometric MTF: |Fourier transform| of the real-ray spot (rays on a square "
    "entrance grid, each carrying its power)",
    "wavelengths add as PSFs do: weight x transmitted power, each at its own chief ray (lateral colour counts)",
    "pixel MTF: |sinc(nu a)| along x and y, a = pitch x sqrt(fill factor) (a centred square sensitive area)",
)


def _pairs(fields, wavelengths) -> tuple[np.ndarray, np.ndarray]:
    """Field/wavelength pairs, field-major: (n, 2) fields (x = 0) and (n,) wavelengths."""
    fdeg = np.array([[0.0, f] for f in fields for _ in wavelengths])
    return fdeg, np.tile(np.asarray(wavelengths, dtype=np.float64), len(fields))


def _combined(otfs, power, chief_xy, weights, freq, nf) -> np.ndarray:
    """Per field (nf, 2, F): the per-pair OTFs (n, 2, F) added over wavelengths (`otf.combine`)."""
    nw = len(weights)
    out = np.empty((nf, 2, len(freq)), dtype=np.complex128)
    for f in range(nf):
        sl = slice(f * nw, (f + 1) * nw)
        w = np.asarray(weights) * power[sl]
        for d, column in ((0, 1), (1, 0)):  # tangential: y offsets; sagittal: x offsets
            offsets = chief_xy[sl, column] - chief_xy[sl.start, column]
            out[f, d] = combine(otfs[sl, d], w, offsets, freq)
    return out


def lens_otf(
    lens, fields, wavelengths, weights, freq, pupil_samples: int | None, aberrated: bool = True
) -> tuple[np.ndarray, list[str]]:
    """Diffraction OTFs (fields, 2, F) at `freq` (cycles/mm), [tangential, sagittal], over the weighted
    wavelengths; with `aberrated` False the same pupils without their wavefront error (the diffraction
    limit). `pupil_samples` None: options.PUPIL_SAMPLES, and for a field whose wavefront that grid does not
    resolve (a phase step above STEP a cell) the count that does, up to options.MOST_PUPIL_SAMPLES (the
    fisheye at 63°: 256 samples put its tangential MTF50 at 1.75 cycles/mm, the refined grid at 1.94). Also the
    warnings: a pupil grid still too coarse."""
    fdeg, wl = _pairs(fields, wavelengths)
    otfs = np.empty((len(wl), 2, len(freq)), dtype=np.complex128)
    power, chief_xy, warnings = np.empty(len(wl)), np.empty((len(wl), 2)), []
    for start in range(0, len(wl), CHUNK):
        sl = slice(start, min(len(wl), start + CHUNK))
        pf = pupil_function(lens, fdeg[sl], wl[sl], pupil_samples or O.PUPIL_SAMPLES)
        steps, _, need = sampling_need(pf, 1.0, 1)
        for i in range(sl.stop - sl.start):
            one, index, samples = pf, i, pf.alpha.shape[1]
            if pupil_samples is None and aberrated and steps[i] > STEP and samples < O.MOST_PUPIL_SAMPLES:
                samples = int(min(np.ceil(need[i] * (np.pi / 2) / STEP / 8) * 8, O.MOST_PUPIL_SAMPLES))
                one, index = (
                    pupil_function(lens, fdeg[start + i : start + i + 1], wl[start + i : start + i + 1], samples),
                    0,
                )
            otfs[start + i], power[start + i], chief_xy[start + i] = _pair_otf(one, index, freq, aberrated)
            warnings += _sampling_warnings(one, index, fdeg[start + i], samples)
    return _combined(otfs, power, chief_xy, weights, freq, len(fields)), warnings[:1]


def _pair_otf(pf, index: int, freq, aberrated: bool):
    """The [tangential, sagittal] OTF at `freq` of pupil `index` of `pf` (its wavefront zeroed unless
    `aberrated`), its transmitted power and its chief ray's image point."""
    if not aberrated:
        pf.opd_mm[index] = 0.0
    otf = [at_frequencies(*pupil_line_otf(pf, index, axis), freq) for axis in AXES.values()]
    return otf, pf.transmission[index], pf.chief.image_xy[index]


def _sampling_warnings(pf, index: int, field, samples: int) -> list[str]:
    """A warning where the pupil grid of `pf`'s pupil `index` may under-resolve the wavefront (a phase step
    above STEP per cell; the MTF often converges sooner)."""
    steps, _, need = sampling_need(pf, 1.0, 1)
    if not steps[index] > STEP:
        return []
    return [
        f"pupil samples {samples} may under-resolve the wavefront at field {field[1]:g} deg, "
        f"{pf.wavelength_nm[index]:g} nm (phase steps up to {steps[index]:.1f} rad per cell): check the diffraction "
        f"MTF there with --pupil-samples {int(max(np.ceil(need[index] * (np.pi / 2) / STEP), 2 * samples))}"
    ]


def geometric_otf(lens, fields, wavelengths, weights, freq, rays: int) -> np.ndarray:
    """Geometric OTFs (fields, 2, F) at `freq` from rays × rays entrance grids, over the wavelengths."""
    fdeg, wl = _pairs(fields, wavelengths)
    chief = chief_rays(lens, fdeg, wl)
    hits = entrance_grid_hits(lens, fdeg, wl, rays, chief)
    otfs = np.empty((len(wl), 2, len(freq)), dtype=np.complex128)
    power = np.empty(len(wl))
    for i, (x_um, y_um, p) in enumerate(hits):
        power[i] = p.sum()
        otfs[i] = (spot_otf(y_um * 1e-3, p, freq), spot_otf(x_um * 1e-3, p, freq)) if p.size else 0.0
    return _combined(otfs, power, chief.image_xy, weights, freq, len(fields))


@dataclass(frozen=True, kw_only=True)
class MTF(Result):
    """MTF curves at chosen fields: `diffraction`, `geometric` (fields, 2, F) [tangential, sagittal] at
    `frequency_cy_mm` (F,); `limit` (F,): the aberration-free tangential MTF of the first field's pupil;
    `pixel` (F,) or None."""

    fields_deg: tuple[float, ...]
    frequency_cy_mm: np.ndarray
    diffraction: np.ndarray
    geometric: np.ndarray
    limit: np.ndarray
    pixel: np.ndarray | None

    def table(self) -> Table:
        columns = [
            "field_deg",
            "frequency_cy_mm",
            "diffraction_limit",
            "tangential",
            "sagittal",
            "geometric_tangential",
            "geometric_sagittal",
        ]
        if self.pixel is not None:
            columns += ["pixel", "tangential_with_pixel", "sagittal_with_pixel"]
        rows, summary = [], {"mtf50_cy_mm": {}}
        for i, f in enumerate(self.fields_deg):
            for k, nu in enumerate(self.frequency_cy_mm):
                row = [
                    f,
                    float(nu),
                    float(self.limit[k]),
                    *self.diffraction[i, :, k].tolist(),
                    *self.geometric[i, :, k].tolist(),
                ]
                if self.pixel is not None:
                    row += [float(self.pixel[k]), *(self.diffraction[i, :, k] * self.pixel[k]).tolist()]
                rows.append(tuple(row))
            summary["mtf50_cy_mm"][f"{f:g}"] = {
                d: mtf50(self.diffraction[i, j], self.frequency_cy_mm) for j, d in enumerate(DIRECTIONS)
            }
        return Table(tuple(columns), tuple(rows), summary)

    def plot(self):
        panels = [("diffraction", self.diffraction), ("geometric", self.geometric)]
        if self.pixel is not None:
            panels.append(("diffraction x pixel", self.diffraction * self.pixel))
        fig, axes = figures.figure(self, len(panels), columns=3)
        nu = self.frequency_cy_mm
        for ax, (title, data) in zip(axes, panels):
            ax.plot(
                nu,
                self.limit * (self.pixel if title.endswith("pixel") else 1.0),
                color="black",
                lw=0.8,
                label="diffraction limit",
            )
            for i, (f, colour) in enumerate(zip(self.fields_deg, figures.colours(len(self.fields_deg)))):
                for j, d in enumerate(DIRECTIONS):
                    ax.plot(nu, data[i, j], color=colour, ls=figures.LINESTYLES[d], label=f"{f:g} deg {d[0].upper()}")
            if title.endswith("pixel"):
                ax.plot(nu, self.pixel, color="grey", ls=":", label="pixel")
            ax.set(
                title=f"{title} MTF",
                xlabel="spatial frequency (cycles/mm)",
                ylabel="MTF",
                xlim=(0, nu[-1]),
                ylim=(0, 1.02),
            )
            ax.grid(alpha=0.3)
            figures.legend(ax, ncols=2)
        return fig


def mtf(
    lens,
    fields_deg=None,
    wavelengths_nm=None,
    weights=None,
    max_frequency_cy_mm=None,
    pupil_samples: int | None = None,
    rays: int = O.GEOMETRIC_RAYS,
    pixel_pitch_um=None,
    fill_factor: float = 1.0,
) -> MTF:
    """MTF against frequency (0 … `max_frequency_cy_mm`, default the cut-off) at `fields_deg` (y,
    degrees; default 0, 0.5, 0.7, 1 × the half field), diffraction and geometric, tangential and
    sagittal, over `wavelengths_nm` with `weights`; `pixel_pitch_um`: also the pixels' MTF."""
    fields = inputs.fields(lens, fields_deg)
    wl, w8 = inputs.wavelengths(lens, wavelengths_nm, weights)
    top = inputs.max_frequency(lens, max_frequency_cy_mm, wl)
    samples = inputs.pupil_samples(pupil_samples)
    rays = inputs.count(rays, "rays", 8)
    pitch, fill = inputs.pixel(pixel_pitch_um, fill_factor)
    freq = np.linspace(0.0, top, O.FREQUENCY_SAMPLES)
    diffraction, warnings = lens_otf(lens, fields, wl, w8, freq, samples)
    limit, _ = lens_otf(lens, fields[:1], wl, w8, freq, samples, aberrated=False)
    geometric = geometric_otf(lens, fields, wl, w8, freq, rays)
    return MTF.of(
        lens,
        "mtf",
        conventions=CONVENTIONS,
        warnings=warnings,
        inputs={
            "fields_deg": fields,
            "wavelengths_nm": wl,
            "weights": w8,
            "max_frequency_cy_mm": top,
            "pupil_samples": samples,
            "rays": rays,
            "pixel_pitch_um": pitch,
            "fill_factor": fill,
        },
        fields_deg=fields,
        frequency_cy_mm=freq,
        diffraction=np.abs(diffraction),
        geometric=np.abs(geometric),
        limit=np.abs(limit[0, 0]),
        pixel=None if pitch is None else pixel_mtf(freq, pitch, fill),
    )
