"""Spot diagrams over fields and wavelengths (`optics.spot.spot`, hexapolar pupil pattern): every
wavelength's rays on the image plane about the primary wavelength's chief ray (so lateral colour
shows), with each one's RMS radius about its centroid and the Airy disc."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..optics.paraxial import paraxial
from ..optics.spot import spot
from . import figures, inputs
from . import options as O
from .base import Result, Table


@dataclass(frozen=True, kw_only=True)
class Spots(Result):
    """`points[i][j]`: (2, rays) image-plane offsets (µm) of field i, wavelength j from the primary
    wavelength's chief ray (or, where that is blocked, the centroid of its light); `airy_um`."""

    fields_deg: tuple[float, ...]
    wavelengths_nm: tuple[float, ...]
    points: tuple[tuple[np.ndarray, ...], ...]
    airy_um: float

    def radii(self) -> dict:
        """Per field and wavelength (and all wavelengths, "all"): RMS radius about the centroid and the
        largest distance from it (GEO), µm."""
        out = {}
        for f, per_field in zip(self.fields_deg, self.points):
            entry = {}
            for label, p in [
                *((f"{w:g}", p) for w, p in zip(self.wavelengths_nm, per_field)),
                ("all", np.concatenate(per_field, axis=1)),
            ]:
                d = np.hypot(*(p - p.mean(axis=1, keepdims=True)))
                entry[label] = {"rms_um": float(np.sqrt(np.mean(d**2))), "geo_um": float(d.max())}
            out[f"{f:g}"] = entry
        return out

    def table(self) -> Table:
        rows = tuple(
            (f, w, float(x), float(y))
            for f, per_field in zip(self.fields_deg, self.points)
            for w, p in zip(self.wavelengths_nm, per_field)
            for x, y in p.T
        )
        return Table(
            ("field_deg", "wavelength_nm", "x_um", "y_um"),
            rows,
            {"airy_radius_um": self.airy_um, "radii": self.radii()},
        )

    def plot(self):
        nf = len(self.fields_deg)
        fig, axes = figures.figure(self, nf, columns=min(nf, 4), size=(3.4, 3.6))
        radii = self.radii()
        for ax, f, per_field in zip(axes, self.fields_deg, self.points):
            for w, p in zip(self.wavelengths_nm, per_field):
                ax.plot(p[0], p[1], ".", ms=1.5, color=figures.wavelength_colour(w), label=f"{w:g} nm")
            centre = np.concatenate(per_field, axis=1).mean(axis=1)
            circle = np.linspace(0, 2 * np.pi, 181)
            ax.plot(
                centre[0] + self.airy_um * np.cos(circle),
                centre[1] + self.airy_um * np.sin(circle),
                color="black",
                lw=0.7,
                label="Airy disc",
            )
            ax.set_aspect("equal", adjustable="datalim")
            ax.set(title=f"{f:g} deg: RMS {radii[f'{f:g}']['all']['rms_um']:.3g} um", xlabel="x (um)", ylabel="y (um)")
            ax.grid(alpha=0.3)
        figures.legend(axes[0], markerscale=6)
        return fig


def spot_diagram(lens, fields_deg=None, wavelengths_nm=None, rings: int = O.SPOT_RINGS) -> Spots:
    """Spot diagrams at `fields_deg` and `wavelengths_nm` (hexapolar pattern of `rings` rings)."""
    fields = inputs.fields(lens, fields_deg)
    wl, _ = inputs.wavelengths(lens, wavelengths_nm)
    rings = inputs.count(rings, "rings", 1, 200)
    primary = inputs.wavelength(lens, None)
    points = []
    for f in fields:
        reference = spot(lens, (0.0, f), primary, "hexapolar", 1)
        ox, oy = reference.origin_mm or reference.chief_ray_mm
        per_field = []
        for w in wl:
            s = spot(lens, (0.0, f), w, "hexapolar", rings)
            sx, sy = s.origin_mm or s.chief_ray_mm
            per_field.append(np.stack([s.x_um + (sx - ox) * 1e3, s.y_um + (sy - oy) * 1e3]))
        points.append(tuple(per_field))
    airy = 1.22 * primary * 1e-3 * paraxial(lens, primary).working_f_number
    return Spots.of(
        lens,
        "spot-diagram",
        conventions=(
            "fields on +y (degrees); image-plane offsets from the primary wavelength's chief ray, um (+y up)",
            f"Airy radius 1.22 lambda N at the primary wavelength {primary:g} nm, N the working f-number",
            "RMS radius about the centroid; GEO: the largest distance from it",
        ),
        inputs={"fields_deg": fields, "wavelengths_nm": wl, "rings": rings, "primary_nm": primary},
        fields_deg=fields,
        wavelengths_nm=wl,
        points=tuple(points),
        airy_um=airy,
    )
