"""Ray fans and OPD fans: along the pupil's y line (tangential fan, Py from −1 to 1, Px = 0) and x line
(sagittal fan), per field and wavelength, the transverse ray aberration on the image plane (µm;
tangential: y error, sagittal: x error, both from the primary wavelength's chief ray, so lateral colour
shows) or the wavefront W (waves, about each wavelength's own chief ray; `rays`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import figures, inputs
from . import options as O
from .base import Result, Table, defined
from .rays import pupil_rays

KINDS = {"ray-fan": ("error_um", "transverse ray aberration (um)"), "opd-fan": ("opd_waves", "OPD (waves)")}
CONVENTIONS = (
    "fields on +y (degrees); normalised pupil coordinates: points of the stop (real ray aiming), 1 at its rim",
    "tangential fan: Py from -1 to 1 at Px = 0 (y errors); sagittal fan: Px at Py = 0 (x errors)",
    "ray errors: image-plane point minus the primary wavelength's chief ray's, um",
    "OPD: W = OPL(chief) - OPL(ray) to the reference sphere about each wavelength's chief-ray image point, waves",
)


@dataclass(frozen=True, kw_only=True)
class Fans(Result):
    """`tangential`, `sagittal` (fields, wavelengths, samples) at `pupil` (samples,) in the unit of
    `KINDS[name]`; NaN where the ray is blocked."""

    fields_deg: tuple[float, ...]
    wavelengths_nm: tuple[float, ...]
    pupil: np.ndarray
    tangential: np.ndarray
    sagittal: np.ndarray

    def table(self) -> Table:
        column = KINDS[self.name][0]
        rows = tuple(
            (f, w, float(p), defined(self.tangential[i, j, k]), defined(self.sagittal[i, j, k]))
            for i, f in enumerate(self.fields_deg)
            for j, w in enumerate(self.wavelengths_nm)
            for k, p in enumerate(self.pupil)
        )
        return Table(("field_deg", "wavelength_nm", "pupil", f"tangential_{column}", f"sagittal_{column}"), rows)

    def plot(self):
        fig, axes = figures.figure(self, 2 * len(self.fields_deg), size=(4.0, 2.8), sharey="row")
        label = KINDS[self.name][1]
        for i, f in enumerate(self.fields_deg):
            for ax, data, direction, axis in (
                (axes[2 * i], self.tangential, "tangential", "Py"),
                (axes[2 * i + 1], self.sagittal, "sagittal", "Px"),
            ):
                for j, w in enumerate(self.wavelengths_nm):
                    ax.plot(self.pupil, data[i, j], color=figures.wavelength_colour(w), label=f"{w:g} nm")
                ax.axhline(0.0, color="black", lw=0.6)
                ax.set(title=f"{f:g} deg, {direction}", xlabel=f"pupil {axis}", ylabel=label, xlim=(-1, 1))
                ax.yaxis.set_tick_params(labelleft=True)
                ax.grid(alpha=0.3)
        figures.legend(axes[1])
        return fig


def _fans(lens, name: str, fields_deg, wavelengths_nm, fan_samples: int) -> Fans:
    fields = inputs.fields(lens, fields_deg)
    wl, _ = inputs.wavelengths(lens, wavelengths_nm)
    n = inputs.count(fan_samples, "fan samples", 3)
    primary = inputs.wavelength(lens, None)
    every = (*wl, primary)  # the primary's chief ray is the ray fans' reference
    t = np.linspace(-1.0, 1.0, n)
    zero = np.zeros(n)
    px, py = np.concatenate([zero, t]), np.concatenate([t, zero])
    rays = pupil_rays(lens, np.repeat(fields, len(every)), np.tile(every, len(fields)), px, py)
    shape = (len(fields), len(every), 2 * n)
    if name == "opd-fan":
        values = rays.wavefront_waves.reshape(shape)
        tangential, sagittal = values[:, :-1, :n], values[:, :-1, n:]
    else:
        chief = rays.chief.image_xy.reshape(len(fields), len(every), 2)[:, -1]  # the primary's
        ok = rays.ok.reshape(shape)
        y = np.where(ok, rays.y_mm.reshape(shape), np.nan) - chief[:, None, None, 1]
        x = np.where(ok, rays.x_mm.reshape(shape), np.nan) - chief[:, None, None, 0]
        tangential, sagittal = y[:, :-1, :n] * 1e3, x[:, :-1, n:] * 1e3
    return Fans.of(
        lens,
        name,
        conventions=CONVENTIONS,
        inputs={"fields_deg": fields, "wavelengths_nm": wl, "fan_samples": n, "primary_nm": primary},
        fields_deg=fields,
        wavelengths_nm=wl,
        pupil=t,
        tangential=tangential,
        sagittal=sagittal,
    )


def ray_fan(lens, fields_deg=None, wavelengths_nm=None, fan_samples: int = O.FAN_SAMPLES) -> Fans:
    """Transverse ray aberration (µm) along the tangential and sagittal pupil lines."""
    return _fans(lens, "ray-fan", fields_deg, wavelengths_nm, fan_samples)


def opd_fan(lens, fields_deg=None, wavelengths_nm=None, fan_samples: int = O.FAN_SAMPLES) -> Fans:
    """The wavefront W (waves) along the tangential and sagittal pupil lines."""
    return _fans(lens, "opd-fan", fields_deg, wavelengths_nm, fan_samples)
