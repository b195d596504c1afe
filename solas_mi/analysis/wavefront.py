"""The wavefront map: W (waves; `rays`) over the pupil on an N × N grid of normalised pupil points
inside the unit disc, its RMS and peak-to-valley, and its Zernike terms (`zernike`), per field at one
wavelength."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import figures, inputs
from . import options as O
from .base import Result, Table
from .rays import pupil_rays
from .zernike import fit, indices

CONVENTIONS = (
    "fields on +y (degrees); normalised pupil coordinates: points of the stop (real ray aiming), 1 at its "
    "rim; rows of the map: Py, columns: Px",
    "W = OPL(chief) - OPL(ray) to the reference sphere about the chief ray's image point through the chief "
    "ray's crossing of the paraxial exit-pupil plane, waves",
)


@dataclass(frozen=True, kw_only=True)
class Wavefront(Result):
    """`maps` (fields, N, N): W in waves at `pupil` × `pupil` (rows: Py, columns: Px; NaN outside the
    pupil or where blocked); `coefficients` (fields, terms) of the `zernike` kind, in waves."""

    fields_deg: tuple[float, ...]
    wavelength_nm: float
    pupil: np.ndarray
    maps: np.ndarray
    zernike: str
    coefficients: np.ndarray

    def statistics(self) -> dict:
        """Per field: RMS about the mean and peak-to-valley of W (waves)."""
        out = {}
        for f, w in zip(self.fields_deg, self.maps):
            v = w[np.isfinite(w)]
            out[f"{f:g}"] = {
                "rms_waves": float(np.sqrt(np.mean((v - v.mean()) ** 2))),
                "pv_waves": float(v.max() - v.min()),
            }
        return out

    def table(self) -> Table:
        terms = indices(self.zernike, self.coefficients.shape[1])
        rows = tuple(
            (f, j + 1, n, m, float(self.coefficients[i, j]))
            for i, f in enumerate(self.fields_deg)
            for j, (n, m) in enumerate(terms)
        )
        return Table(("field_deg", "term", "n", "m", "coefficient_waves"), rows, self.statistics())

    def plot(self):
        nf = len(self.fields_deg)
        fig, axes = figures.figure(self, nf + 1, columns=min(nf + 1, 3), size=(3.8, 3.4))
        stats = self.statistics()
        for ax, f, w in zip(axes, self.fields_deg, self.maps):
            top = float(np.nanmax(np.abs(w))) or 1.0
            image = ax.imshow(w, origin="lower", extent=(-1, 1, -1, 1), cmap="RdBu_r", vmin=-top, vmax=top)
            fig.colorbar(image, ax=ax, label="W (waves)", shrink=0.85)
            s = stats[f"{f:g}"]
            ax.set(
                title=f"{f:g} deg\nRMS {s['rms_waves']:.3g}, PV {s['pv_waves']:.3g} waves",
                xlabel="pupil Px",
                ylabel="pupil Py",
            )
            ax.title.set_fontsize("medium")
        bars = axes[-1]
        terms = np.arange(1, self.coefficients.shape[1] + 1)
        width = 0.8 / nf
        for i, (f, colour) in enumerate(zip(self.fields_deg, figures.colours(nf))):
            bars.bar(
                terms + (i - (nf - 1) / 2) * width, self.coefficients[i], width=width, color=colour, label=f"{f:g} deg"
            )
        bars.axhline(0.0, color="black", lw=0.6)
        bars.set(title=f"{self.zernike} Zernike terms", xlabel="term", ylabel="coefficient (waves)")
        bars.grid(alpha=0.3)
        figures.legend(bars)
        return fig


def wavefront(
    lens,
    fields_deg=None,
    wavelength_nm=None,
    pupil_samples: int | None = None,
    zernike: str = O.ZERNIKE,
    zernike_terms: int = O.ZERNIKE_TERMS,
) -> Wavefront:
    """W over the pupil and its `zernike_terms` Zernike terms of kind `zernike` ("fringe" or "noll") at
    `fields_deg` and `wavelength_nm` (default the primary)."""
    fields = inputs.fields(lens, fields_deg)
    wl = inputs.wavelength(lens, wavelength_nm)
    n = inputs.pupil_samples(pupil_samples) or O.PUPIL_SAMPLES
    terms = indices(zernike, zernike_terms)
    t = np.linspace(-1.0, 1.0, n)
    px, py = np.meshgrid(t, t)
    inside = np.hypot(px, py) <= 1.0
    rays = pupil_rays(lens, fields, np.full(len(fields), wl), px[inside], py[inside])
    maps = np.full((len(fields), n, n), np.nan)
    coefficients = np.empty((len(fields), len(terms)))
    warnings = []
    for i in range(len(fields)):
        ok = rays.ok[i]
        maps[i][inside] = rays.wavefront_waves[i]
        coefficients[i] = fit(zernike, len(terms), px[inside][ok], py[inside][ok], rays.wavefront_waves[i][ok])
        if not ok.all():
            warnings.append(
                f"the pupil at {fields[i]:g} deg is vignetted ({100 * (1 - ok.mean()):.3g} % of the unit "
                "disc blocked): Zernike terms fitted over a cut pupil depend on where it is sampled"
            )
    conventions = (
        *CONVENTIONS,
        f"Zernike terms: {zernike} ({O.ZERNIKE_KINDS[zernike]}), theta from +x toward +y, least-squares "
        "fit over the rays that arrive",
    )
    return Wavefront.of(
        lens,
        "wavefront",
        conventions=conventions,
        warnings=warnings,
        inputs={
            "fields_deg": fields,
            "wavelength_nm": wl,
            "pupil_samples": n,
            "zernike": zernike,
            "zernike_terms": len(terms),
        },
        fields_deg=fields,
        wavelength_nm=wl,
        pupil=t,
        maps=maps,
        zernike=zernike,
        coefficients=coefficients,
    )
