"""Quantum efficiency against wavelength, and the effective QE with which each filter sees each channel
of an RGB irradiance image.

An RGB image (from either engine) is read as a spectrum the way the render reads one
(`solas_mi.render.response.RGB_BANDS_NM`): channel B covers 380–500 nm, G 500–590 nm, R 590–780 nm
(the outer edges are the sRGB response's range, `SRGB_RANGE_NM`), and a pixel's channel c holds the
irradiance E_c (W/m²) of its band spread evenly over it (spectral irradiance E_c / Δλ_c). A photon of
wavelength λ carries hc/λ, so the band's photons per unit wavelength grow as λ, and a pixel of area A
with filter f exposed for t collects on average (EMVA 1288 release 4.0, eqs. 1 and 2 per wavelength)

    μ_e,f = Σ_c Q[f, c] μ_p,c,    μ_p,c = A E_c t λ̄_c / (h c),
    Q[f, c] = ∫_band c QE_f(λ) λ dλ / ∫_band c λ dλ,

with λ̄_c the band's centre: Q[f, c] is the photon-weighted mean QE of filter f over band c, and the
electrons per unit irradiance are M[f, c] = Q[f, c] A t λ̄_c / (h c). Cross-talk is included: a red
filter that passes some green gives Q[R, G] > 0. The scalar model (one QE η_f per filter, one
wavelength λ_c per channel) is the special case Q[f, c] = η_f for the channels the filter collects
(`cfa.CHANNELS`) and 0 elsewhere: exactly what a curve equal to η_f over those bands and 0 elsewhere
gives, with λ_c the band centres.

A curve is given at sample wavelengths, piecewise linear between them (a repeated wavelength is a
step) and 0 outside them; its integrals are exact (Simpson's rule on each piece, where QE·λ is a
quadratic).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import SolasError
from ..render.response import RGB_BANDS_NM, SRGB_RANGE_NM
from ..userfiles import read_text
from .cfa import CHANNELS, FILTERS

# the bands of image channels R, G, B (nm)
BANDS_NM = (
    (RGB_BANDS_NM[1], SRGB_RANGE_NM[1]),
    (RGB_BANDS_NM[0], RGB_BANDS_NM[1]),
    (SRGB_RANGE_NM[0], RGB_BANDS_NM[0]),
)
BAND_CENTRES_NM = tuple(0.5 * (lo + hi) for lo, hi in BANDS_NM)
WAVELENGTH = "wavelength_nm"


@dataclass(frozen=True)
class QECurve:
    """Quantum efficiency (0–1) of each filter named in `filters` (letters of `cfa.FILTERS`) at the
    wavelengths `wavelength_nm` (non-decreasing; a repeated wavelength is a step); `qe[i]` is filter
    `filters[i]`'s column."""

    wavelength_nm: tuple[float, ...]
    filters: tuple[str, ...]
    qe: tuple[tuple[float, ...], ...]

    @classmethod
    def from_table(cls, table: dict, where: str = "qe_curve") -> QECurve:
        """A curve from columns {"wavelength_nm": [...], "R": [...], ...}; `where` names it in errors."""
        if not isinstance(table, dict):
            raise SolasError(
                f"{where} must be a table of columns ({WAVELENGTH} and filters R, G, B, C), got {type(table).__name__}"
            )
        unknown = sorted(set(table) - {WAVELENGTH, *FILTERS})
        if unknown or WAVELENGTH not in table:
            raise SolasError(
                f"{where}: columns {', '.join(unknown) or '(none)'} unknown or {WAVELENGTH} missing; "
                f"allowed: {WAVELENGTH} and the filters {', '.join(FILTERS)}"
            )
        filters = tuple(f for f in FILTERS if f in table)
        columns = [_column(table[WAVELENGTH], f"{where} {WAVELENGTH}")]
        columns += [_column(table[f], f"{where} {f}") for f in filters]
        if not filters or len({len(c) for c in columns}) != 1 or len(columns[0]) < 2:
            raise SolasError(
                f"{where}: needs {WAVELENGTH} and at least one filter column, all of one length "
                f">= 2 (got lengths {', '.join(str(len(c)) for c in columns)})"
            )
        lam = np.array(columns[0])
        if np.any(lam <= 0) or np.any(np.diff(lam) < 0):
            raise SolasError(f"{where}: {WAVELENGTH} must be > 0 and non-decreasing (a repeated wavelength is a step)")
        for name, column in zip(filters, columns[1:]):
            if min(column) < 0 or max(column) > 1:
                raise SolasError(
                    f"{where}: filter {name}'s quantum efficiency must be in [0, 1] "
                    f"(found {min(column):g} to {max(column):g}); give fractions, not %"
                )
        return cls(tuple(columns[0]), filters, tuple(tuple(c) for c in columns[1:]))

    def table(self) -> dict:
        """The columns (JSON- and TOML-ready), as `from_table` reads them."""
        return {WAVELENGTH: list(self.wavelength_nm), **{f: list(c) for f, c in zip(self.filters, self.qe)}}

    def check_filters(self, cfa_filters) -> None:
        """SolasError unless the curve has a column for every filter in `cfa_filters`."""
        missing = sorted(set(cfa_filters) - set(self.filters), key=FILTERS.index)
        if missing:
            raise SolasError(
                f"qe_curve has no column for filter(s) {', '.join(missing)} of the colour filter array "
                f"(columns: {', '.join(self.filters)})"
            )

    def check_response(self, cfa_filters) -> None:
        """SolasError unless every filter in `cfa_filters` has some quantum efficiency inside the channels'
        bands (a filter blind there reads black whatever the light, and no colour matrix inverts it)."""
        qe = self.effective_qe(cfa_filters)
        blind = [f for f in sorted(set(cfa_filters), key=FILTERS.index) if not qe[FILTERS.index(f)].any()]
        if blind:
            raise SolasError(
                f"qe_curve: filter(s) {', '.join(blind)} of the colour filter array have zero quantum "
                f"efficiency over {SRGB_RANGE_NM[0]:g}–{SRGB_RANGE_NM[1]:g} nm (the bands of the image's "
                "R, G, B); each filter must respond somewhere in them"
            )

    def effective_qe(self, cfa_filters) -> np.ndarray:
        """Q[f, c] (4 × 3, rows in `cfa.FILTERS` order): the photon-weighted mean QE of filter f over the
        band of channel c (module docstring). Every filter in `cfa_filters` needs a column."""
        self.check_filters(cfa_filters)
        out = np.zeros((len(FILTERS), len(BANDS_NM)))
        for name, column in zip(self.filters, self.qe):
            for c, (lo, hi) in enumerate(BANDS_NM):
                out[FILTERS.index(name), c] = _integral(self.wavelength_nm, column, lo, hi) / (
                    0.5 * (hi * hi - lo * lo)
                )
        return out


def _column(values, where: str) -> list[float]:
    if not isinstance(values, (list, tuple)) or not all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) for v in values
    ):
        raise SolasError(f"{where} must be a list of finite numbers")
    return [float(v) for v in values]


def _integral(lam, qe, lo: float, hi: float) -> float:
    """∫_lo^hi QE(λ) λ dλ of the piecewise linear curve (0 outside its samples), exact."""
    x, y = np.asarray(lam), np.asarray(qe)
    a, b = np.maximum(x[:-1], lo), np.minimum(x[1:], hi)
    width = x[1:] - x[:-1]
    keep = (b > a) & (width > 0)
    x0, x1, y0, y1, a, b = x[:-1][keep], x[1:][keep], y[:-1][keep], y[1:][keep], a[keep], b[keep]

    def f(t):  # QE(t) · t on the piece
        return (y0 + (y1 - y0) * (t - x0) / (x1 - x0)) * t

    return float(np.sum((b - a) / 6.0 * (f(a) + 4.0 * f(0.5 * (a + b)) + f(b))))


def scalar_effective_qe(qe: dict[str, float]) -> np.ndarray:
    """Q[f, c] of the scalar model: η_f for the channels filter f collects (`cfa.CHANNELS`), else 0."""
    out = np.zeros((len(FILTERS), len(BANDS_NM)))
    for i, name in enumerate(FILTERS):
        out[i, list(CHANNELS[name])] = qe[name]
    return out


def read_csv(path: str | Path) -> QECurve:
    """A curve from a CSV file (`userfiles.read_text`: a regular UTF-8 file of at most its bound): a header
    line naming the columns (wavelength_nm and filter letters, e.g. "wavelength_nm,R,G,B,C"), then one row
    of numbers per wavelength; "#" lines are comments. No message quotes the file (a sensor file may name
    any file)."""
    where = f"QE curve {str(path)!r}"
    rows = [
        line.strip()
        for line in read_text(path, "QE curve").splitlines()
        if line.strip() and not line.lstrip().startswith("#")
    ]
    header = [name.strip() for name in rows[0].split(",")] if rows else []
    allowed = (WAVELENGTH, *FILTERS)
    bad = [i for i, name in enumerate(header, start=1) if name not in allowed or header.index(name) != i - 1]
    if not rows or bad:
        fault = f"header column {bad[0]} is not a column name or repeats one" if rows else "no lines"
        raise SolasError(f"{where}: {fault}; the first line names distinct columns from {', '.join(allowed)}")
    try:
        data = np.loadtxt(rows[1:], delimiter=",", ndmin=2) if len(rows) > 1 else np.zeros((0, len(header)))
    except ValueError:
        raise SolasError(
            f"{where} is not a CSV table of numbers under a header line of column names ({WAVELENGTH},R,G,B,C)"
        ) from None
    if data.shape[1] != len(header):
        raise SolasError(f"{where}: the header names {len(header)} distinct columns, the rows hold {data.shape[1]}")
    return QECurve.from_table({name: data[:, i].tolist() for i, name in enumerate(header)}, where)
