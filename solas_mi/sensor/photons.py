"""`PhotonConversion`, the head of every sensor's chain: light on a pixel → its mean photo-electrons.

A square pixel of pitch p behind the colour filter array's filter f collects from an irradiance image
(W/m², channels R, G, B) exposed t seconds the mean photo-electrons μ_e = Σ_c Q[f, c] μ_p,c (EMVA 1288
eqs. 1 and 2; `exposure.photons`, `cfa.mosaic`), with the effective quantum efficiencies Q of scalar
values per filter or of QE curves (`qe`). A readout's photodiode sees a share of these (its sensitivity)
over its exposure's window of time (`readout`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numpy as np

from ..errors import SolasError
from .cfa import check_pattern, mosaic
from .exposure import photons
from .limits import check_number, check_ranged
from .qe import BAND_CENTRES_NM, QECurve, scalar_effective_qe

# the scalar quantum efficiencies and channel wavelengths (nm) of a sensor described without a QE curve
SCALAR_DEFAULTS = {"qe_r": 0.6, "qe_g": 0.7, "qe_b": 0.5, "qe_c": 0.8, "wavelengths_nm": (610.0, 540.0, 465.0)}


@dataclass(frozen=True)
class PhotonConversion:
    """Pixel pitch (µm), the colour filter array, and the quantum efficiency per filter (R, G, B, clear)
    with the representative wavelength of the image's three channels, or instead a QE curve per filter
    (`qe.QECurve`). The scalar fields left out take `SCALAR_DEFAULTS`."""

    pixel_pitch_um: float = 3.0
    qe_r: float | None = None  # default 0.6 (SCALAR_DEFAULTS), None with a qe_curve
    qe_g: float | None = None  # 0.7
    qe_b: float | None = None  # 0.5
    qe_c: float | None = None  # 0.8
    wavelengths_nm: tuple[float, float, float] | None = None  # (610, 540, 465)
    cfa: str = "RGGB"
    qe_curve: QECurve | None = None

    def __post_init__(self):
        check_ranged(self.pixel_pitch_um, "pixel_pitch_um")
        if self.qe_curve is None:
            self._check_scalar_qe()
        elif not isinstance(self.qe_curve, QECurve):
            raise SolasError(f"sensor qe_curve must be a QECurve, got {type(self.qe_curve).__name__}")
        elif given := [name for name in SCALAR_DEFAULTS if getattr(self, name) is not None]:
            raise SolasError(
                f"sensor qe_curve and {', '.join(given)} both given: a QE curve replaces the scalar "
                f"quantum efficiencies and sets the channel wavelengths; give one or the other"
            )
        check_pattern(self.cfa)
        if self.qe_curve is not None:
            self.qe_curve.check_filters(self.cfa)
            self.qe_curve.check_response(self.cfa)

    def _check_scalar_qe(self) -> None:
        """Fill the scalar fields left out with their defaults and check them."""
        for name, default in SCALAR_DEFAULTS.items():
            if getattr(self, name) is None:
                object.__setattr__(self, name, default)
        for name in ("qe_r", "qe_g", "qe_b", "qe_c"):
            check_number(getattr(self, name), name, 0.0, 1.0, "a quantum efficiency", open_low=True)
        if not isinstance(self.wavelengths_nm, (tuple, list)) or len(self.wavelengths_nm) != 3:
            raise SolasError(
                f"sensor wavelengths_nm = {self.wavelengths_nm!r} must be three wavelengths (R, G, B) in nm"
            )
        for value in self.wavelengths_nm:
            check_ranged(value, "wavelengths_nm")
        object.__setattr__(self, "wavelengths_nm", tuple(float(v) for v in self.wavelengths_nm))

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    def describe(self) -> dict:
        """Every value (JSON-ready; a QE curve as its table of columns)."""
        values = {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items() if k != "qe_curve"}
        values["qe_curve"] = None if self.qe_curve is None else self.qe_curve.table()
        return values

    @property
    def channel_wavelengths_nm(self) -> tuple[float, float, float]:
        """The wavelength (nm) that stands for each image channel R, G, B: `wavelengths_nm`, or with a QE
        curve the centres of the channels' bands (`qe` module)."""
        return self.wavelengths_nm if self.qe_curve is None else BAND_CENTRES_NM

    def effective_qe(self) -> np.ndarray:
        """Q[f, c] (4 × 3, filters in `cfa.FILTERS` order, channels R, G, B): the electrons per photon of
        channel c (at `channel_wavelengths_nm`) on a pixel of filter f (`qe` module)."""
        if self.qe_curve is None:
            return scalar_effective_qe({"R": self.qe_r, "G": self.qe_g, "B": self.qe_b, "C": self.qe_c})
        return self.qe_curve.effective_qe(set(self.cfa))

    def mean_electrons(self, irradiance: np.ndarray, exposure_s: float) -> np.ndarray:
        """The noise-free photo-electrons of each pixel (H, W) of an irradiance image (H, W, 3) in W/m²
        exposed `exposure_s` seconds."""
        mu_p = photons(irradiance, exposure_s, self.pixel_pitch_um, self.channel_wavelengths_nm)
        return mosaic(mu_p, self.cfa, self.effective_qe())
