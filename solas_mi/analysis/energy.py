"""Encircled and ensquared energy: the fraction of the light reaching the image that falls within a
circle of radius r (a square of half width r) about the PSF's centroid or the chief ray, from the
diffraction PSF (`psf.psf`, Fraunhofer, its window grown until it holds the light) and, beside it,
from the geometric spot (rays on an entrance grid, each carrying its power)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..optics.paraxial import paraxial
from ..optics.pupil import chief_rays
from ..psf import psf
from ..psf.geometric import entrance_grid_hits
from . import figures, inputs
from . import options as O
from .base import Result, Table

RADII = 201  # radii from 0 to the largest
PITCH_FRACTION = 0.1  # PSF pitch: this fraction of λN
START_SIZE = 256  # PSF window before it grows
GEOMETRIC_RAYS = 256
NEAR, SUB = 24, 8  # pixels within NEAR pitches of the centre split into SUB × SUB points


def cumulative(distance: np.ndarray, weight: np.ndarray, radii: np.ndarray, spread: float = 0.0) -> np.ndarray:
    """The weight within each of `radii` (by `distance`: Euclidean for circles, Chebyshev for squares):
    of points (`spread` 0), or of weights each spread evenly over ±spread/2 about its distance."""
    if spread <= 0:
        order = np.argsort(distance)
        total = np.concatenate([[0.0], np.cumsum(weight[order])])
        return total[np.searchsorted(distance[order], radii, side="right")]
    step = spread / 8.0
    first = np.floor((distance - spread / 2.0) / step).astype(np.int64)  # the first bin each weight covers
    low = min(int(first.min()), 0)
    binned = np.convolve(np.bincount(first - low, weights=weight), np.ones(8) / 8.0)
    upper = (np.arange(len(binned)) + low + 1) * step  # each bin's upper edge
    return np.interp(radii, upper, np.cumsum(binned), left=0.0)


def split(x: np.ndarray, y: np.ndarray, weight: np.ndarray, pitch: float):
    """A PSF's pixel centres (x, y) and weights, as two sets: the pixels within NEAR pitches of the origin
    as SUB × SUB points each, the others whole (a pixel is not a point: near the centre its extent
    matters); each set with the spread of its points (`cumulative`)."""
    near = np.hypot(x, y) < NEAR * pitch
    offsets = ((np.arange(SUB) + 0.5) / SUB - 0.5) * pitch
    ox, oy = (a.ravel() for a in np.meshgrid(offsets, offsets))
    fine = (
        (x[near][:, None] + ox).ravel(),
        (y[near][:, None] + oy).ravel(),
        np.repeat(weight[near] / SUB**2, SUB * SUB),
    )
    return [(fine, pitch / SUB), ((x[~near], y[~near], weight[~near]), pitch)]


@dataclass(frozen=True, kw_only=True)
class Energy(Result):
    """Per field (`fields_deg`) at `radius_um`: `encircled`, `ensquared` (fields, 2, R): [diffraction,
    geometric]."""

    fields_deg: tuple[float, ...]
    radius_um: np.ndarray
    encircled: np.ndarray
    ensquared: np.ndarray

    def radius_at(self, fraction: float = 0.8) -> dict:
        """Per field, the radius (µm) holding `fraction` of the light, diffraction and geometric."""
        return {
            f"{f:g}": {
                kind: float(np.interp(fraction, self.encircled[i, k], self.radius_um))
                for k, kind in enumerate(("diffraction", "geometric"))
            }
            for i, f in enumerate(self.fields_deg)
        }

    def table(self) -> Table:
        rows = tuple(
            (f, float(r), *self.encircled[i, :, k].tolist(), *self.ensquared[i, :, k].tolist())
            for i, f in enumerate(self.fields_deg)
            for k, r in enumerate(self.radius_um)
        )
        return Table(
            ("field_deg", "radius_um", "encircled", "encircled_geometric", "ensquared", "ensquared_geometric"),
            rows,
            {"radius_80_percent_um": self.radius_at(0.8)},
        )

    def plot(self):
        fig, axes = figures.figure(self, 2, size=(4.8, 3.8))
        for ax, data, what in ((axes[0], self.encircled, "encircled"), (axes[1], self.ensquared, "ensquared")):
            for i, (f, colour) in enumerate(zip(self.fields_deg, figures.colours(len(self.fields_deg)))):
                ax.plot(self.radius_um, data[i, 0], color=colour, label=f"{f:g} deg")
                ax.plot(
                    self.radius_um, data[i, 1], color=colour, ls="--", lw=0.8, label="geometric" if i == 0 else None
                )
            ax.set(
                title=f"{what} energy",
                xlabel="radius (um)" if what == "encircled" else "half width (um)",
                ylabel="fraction of the light",
                ylim=(0, 1.02),
                xlim=(0, self.radius_um[-1]),
            )
            ax.grid(alpha=0.3)
            figures.legend(ax, loc="lower right")
        return fig


def _diffraction(lens, field: float, wl: float, samples: int, pitch: float, reference: str, radii: np.ndarray):
    """Encircled and ensquared energy (2, R) at `radii` of the diffraction PSF (pixels: `split`), and
    its warnings."""
    p = psf(
        lens,
        (0.0, field),
        wl,
        pitch_um=pitch,
        size=START_SIZE,
        pupil_samples=samples,
        normalization="none",
        auto_window=True,
    )
    weight = (p.data * pitch**2).ravel() / p.meta["transmission"]
    x, y = (a.ravel() for a in np.meshgrid(p.x_um, p.y_um))
    if reference == "centroid":
        x, y = x - np.dot(weight, x) / weight.sum(), y - np.dot(weight, y) / weight.sum()
    parts = split(x, y, weight, pitch)
    return np.array(
        [
            sum(cumulative(measure(px, py), w, radii, spread) for (px, py, w), spread in parts)
            for measure in (np.hypot, lambda a, b: np.maximum(abs(a), abs(b)))
        ]
    ), list(p.meta["warnings"])


def _geometric(lens, field: float, wl: float, reference: str, radii: np.ndarray | None = None):
    """Encircled and ensquared energy (2, R) at `radii` of rays on an entrance grid; without `radii`,
    the radius holding 99.5 % of them."""
    fdeg = np.array([[0.0, field]])
    x, y, power = entrance_grid_hits(
        lens, fdeg, np.array([wl]), GEOMETRIC_RAYS, chief_rays(lens, fdeg, np.array([wl]))
    )[0]
    if reference == "centroid":
        x, y = x - np.dot(power, x) / power.sum(), y - np.dot(power, y) / power.sum()
    if radii is None:
        return float(np.percentile(np.hypot(x, y), 99.5))
    return np.array([cumulative(d, power / power.sum(), radii) for d in (np.hypot(x, y), np.maximum(abs(x), abs(y)))])


def encircled_energy(
    lens,
    fields_deg=None,
    wavelength_nm=None,
    pupil_samples: int | None = None,
    energy_reference: str = O.ENERGY_REFERENCES[0],
) -> Energy:
    """Encircled and ensquared energy against radius at `fields_deg`, `wavelength_nm` (default the
    primary), about the PSF's centroid or the chief ray (`energy_reference`)."""
    fields = inputs.fields(lens, fields_deg)
    wl = inputs.wavelength(lens, wavelength_nm)
    samples = inputs.pupil_samples(pupil_samples) or O.PUPIL_SAMPLES
    inputs.choice(energy_reference, O.ENERGY_REFERENCES, "energy reference")
    pitch = PITCH_FRACTION * wl * 1e-3 * paraxial(lens, wl).working_f_number
    largest = max(max(_geometric(lens, f, wl, energy_reference) for f in fields) * 1.2, 5 * pitch / PITCH_FRACTION)
    radii = np.linspace(0.0, largest, RADII)  # to 1.2 × the widest spot's 99.5 % radius, at least 5 λN
    curves, warnings = np.empty((len(fields), 2, 2, RADII)), []
    for i, f in enumerate(fields):
        curves[i, :, 0], w = _diffraction(lens, f, wl, samples, pitch, energy_reference, radii)
        curves[i, :, 1] = _geometric(lens, f, wl, energy_reference, radii)
        warnings += w
    encircled, ensquared = curves[:, 0], curves[:, 1]
    return Energy.of(
        lens,
        "encircled-energy",
        warnings=dict.fromkeys(warnings),
        conventions=(
            "fields on +y (degrees); radius (circles) or half width (squares, sides along x and y) "
            f"about the {energy_reference}, um",
            "fraction of the light reaching the image (the diffraction PSF's window may hold a little less)",
        ),
        inputs={
            "fields_deg": fields,
            "wavelength_nm": wl,
            "pupil_samples": samples,
            "energy_reference": energy_reference,
            "psf_pitch_um": pitch,
        },
        fields_deg=fields,
        radius_um=radii,
        encircled=encircled,
        ensquared=ensquared,
    )
