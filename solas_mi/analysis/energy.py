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
PITCH_FRACTION = 0.25  # PSF pitch: this fraction of λN
START_SIZE = 128  # PSF window before it grows
GEOMETRIC_RAYS = 256


def cumulative(distance: np.ndarray, weight: np.ndarray, radii: np.ndarray, spread: float = 0.0) -> np.ndarray:
    """The weight within each of `radii` (by `distance`: Euclidean for circles, Chebyshev for squares).
    `spread` > 0: each weight is spread evenly over ±spread/2 about its distance (a pixel of that pitch
    is not a point: without it the curve of a sampled PSF climbs in steps)."""
    if spread <= 0:
        order = np.argsort(distance)
        return np.interp(radii, distance[order], np.cumsum(weight[order]), left=0.0)
    step = spread / 8.0
    index = np.floor((distance + spread / 2.0) / step).astype(np.int64)
    binned = np.bincount(index, weights=weight, minlength=int(radii[-1] / step) + 10)
    spread_out = np.convolve(binned, np.ones(8) / 8.0)  # each bin's weight over the 8 bins above its start
    edges = np.arange(1, len(spread_out) + 1) * step - spread / 2.0
    return np.interp(radii, edges, np.cumsum(spread_out), left=0.0)


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
        return {f"{f:g}": {kind: float(np.interp(fraction, self.encircled[i, k], self.radius_um))
                           for k, kind in enumerate(("diffraction", "geometric"))} for i, f in enumerate(self.fields_deg)}

    def table(self) -> Table:
        rows = tuple((f, float(r), *self.encircled[i, :, k].tolist(), *self.ensquared[i, :, k].tolist())
                     for i, f in enumerate(self.fields_deg) for k, r in enumerate(self.radius_um))
        return Table(("field_deg", "radius_um", "encircled", "encircled_geometric", "ensquared", "ensquared_geometric"),
                     rows, {"radius_80_percent_um": self.radius_at(0.8)})

    def plot(self):
        fig, axes = figures.figure(self, 2, size=(4.8, 3.8))
        for ax, data, what in ((axes[0], self.encircled, "encircled"), (axes[1], self.ensquared, "ensquared")):
            for i, (f, colour) in enumerate(zip(self.fields_deg, figures.colours(len(self.fields_deg)))):
                ax.plot(self.radius_um, data[i, 0], color=colour, label=f"{f:g} deg")
                ax.plot(self.radius_um, data[i, 1], color=colour, ls="--", lw=0.8,
                        label="geometric" if i == 0 else None)
            ax.set(title=f"{what} energy", xlabel="radius (um)" if what == "encircled" else "half width (um)",
                   ylabel="fraction of the light", ylim=(0, 1.02), xlim=(0, self.radius_um[-1]))
            ax.grid(alpha=0.3)
            figures.legend(ax, loc="lower right")
        return fig


def _diffraction(lens, field: float, wl: float, samples: int, pitch: float, reference: str):
    """(distances (circle, square) in µm, weights) of the PSF's pixels, its pitch and its warnings."""
    p = psf(lens, (0.0, field), wl, pitch_um=pitch, size=START_SIZE, pupil_samples=samples, normalization="none",
            auto_window=True)
    weight = (p.data * pitch ** 2).ravel() / p.meta["transmission"]
    x, y = np.meshgrid(p.x_um, p.y_um)
    if reference == "centroid":
        x, y = x - np.dot(weight, x.ravel()) / weight.sum(), y - np.dot(weight, y.ravel()) / weight.sum()
    return (np.hypot(x, y).ravel(), np.maximum(abs(x), abs(y)).ravel()), weight, list(p.meta["warnings"])


def _geometric(lens, field: float, wl: float, reference: str):
    """(distances (circle, square) in µm, weights) of rays on an entrance grid."""
    fdeg = np.array([[0.0, field]])
    x, y, power = entrance_grid_hits(lens, fdeg, np.array([wl]), GEOMETRIC_RAYS, chief_rays(lens, fdeg, np.array([wl])))[0]
    if reference == "centroid":
        x, y = x - np.dot(power, x) / power.sum(), y - np.dot(power, y) / power.sum()
    return (np.hypot(x, y), np.maximum(abs(x), abs(y))), power / power.sum()


def encircled_energy(lens, fields_deg=None, wavelength_nm=None, pupil_samples: int = O.PUPIL_SAMPLES,
                     energy_reference: str = O.ENERGY_REFERENCES[0]) -> Energy:
    """Encircled and ensquared energy against radius at `fields_deg`, `wavelength_nm` (default the
    primary), about the PSF's centroid or the chief ray (`energy_reference`)."""
    fields = inputs.fields(lens, fields_deg)
    wl = inputs.wavelength(lens, wavelength_nm)
    samples = inputs.count(pupil_samples, "pupil samples", 16)
    inputs.choice(energy_reference, O.ENERGY_REFERENCES, "energy reference")
    pitch = PITCH_FRACTION * wl * 1e-3 * paraxial(lens, wl).working_f_number
    spreads, warnings = [], []
    for f in fields:
        distances, weight, w = _diffraction(lens, f, wl, samples, pitch, energy_reference)
        spreads.append(((distances, weight), _geometric(lens, f, wl, energy_reference)))
        warnings += w
    largest = max(np.percentile(d[0], 99.5) for pair in spreads for d, _ in pair[1:]) * 1.2
    largest = max(largest, 5 * pitch / PITCH_FRACTION)  # at least 5 λN
    radii = np.linspace(0.0, largest, RADII)
    encircled = np.array([[cumulative(d[0], w, radii, s) for (d, w), s in zip(pair, (pitch, 0.0))] for pair in spreads])
    ensquared = np.array([[cumulative(d[1], w, radii, s) for (d, w), s in zip(pair, (pitch, 0.0))] for pair in spreads])
    return Energy(name="encircled-energy", lens=lens.name, lens_hash=lens.hash, warnings=tuple(dict.fromkeys(warnings)),
                  conventions=("fields on +y (degrees); radius (circles) or half width (squares, sides along x and y) "
                               f"about the {energy_reference}, um", "fraction of the light reaching the image (the "
                               "diffraction PSF's window may hold a little less)"),
                  inputs={"fields_deg": fields, "wavelength_nm": wl, "pupil_samples": samples,
                          "energy_reference": energy_reference, "psf_pitch_um": pitch},
                  fields_deg=fields, radius_um=radii, encircled=encircled, ensquared=ensquared)
