"""Optical glass: the catalogue (Sellmeier) and model glass given by (n_d, V_d).

Indices are relative to air; AIR has index 1. Wavelengths are in nm.

References: the Sellmeier dispersion formula with the coefficients and valid ranges of the SCHOTT
optical glass data sheets (SCHOTT AG, "Optical Glass — Data Sheets"; TIE-29 "Refractive Index and
Dispersion"); model glass from n_d and V_d (Fraunhofer d, F, C lines) as a two-term Cauchy fit.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Callable

import numpy as np
import tomllib

from ..errors import SolasError

CATALOG_PATH = Path(__file__).parent / "data" / "glass_catalog.toml"
# Fraunhofer lines (nm) defining n_d and V_d.
LINE_D, LINE_F, LINE_C = 587.5618, 486.1327, 656.2725
# Range (nm) over which a model glass's two-term dispersion is offered.
MODEL_RANGE_NM = (365.0, 1014.0)
_NUMBER = r"([0-9]+(?:\.[0-9]*)?|\.[0-9]+)"
_MODEL_RE = re.compile(rf"^\s*model\s*:\s*{_NUMBER}\s*(?:/\s*{_NUMBER}\s*)?$", re.IGNORECASE)
# A catalogue glass stands for a table's (n_d, V_d) when both agree within these (its formula's values).
MATCH_ND, MATCH_VD = 5e-5, 0.05


@dataclass(frozen=True)
class Glass:
    """A refractive medium. `kind` is "sellmeier", "model" or "air"."""

    name: str
    kind: str
    coefficients: tuple[tuple[float, ...], tuple[float, ...]] = ((), ())
    range_nm: tuple[float, float] = (0.0, float("inf"))

    def index(self, wavelength_nm: float | np.ndarray) -> np.ndarray | float:
        """Refractive index at `wavelength_nm`; SolasError outside the valid range."""
        wl = np.asarray(wavelength_nm, dtype=np.float64)
        lo, hi = self.range_nm
        if np.any(~np.isfinite(wl)) or np.any(wl < lo) or np.any(wl > hi):
            bad = wl[(wl < lo) | (wl > hi) | ~np.isfinite(wl)] if wl.ndim else wl
            raise SolasError(
                f"wavelength {float(np.atleast_1d(bad)[0]):.10g} nm is outside glass {self.name}'s "
                f"valid range {lo:g}-{hi:g} nm"
            )
        n = self.index_formula(wl / 1000.0, np.sqrt)
        return float(n) if n.ndim == 0 else n

    def index_formula(self, wavelength_um, sqrt: Callable):
        """n(λ) with λ in µm for any array type (NumPy, Dr.Jit) given its `sqrt`; no range check."""
        if self.kind == "air":
            return wavelength_um * 0.0 + 1.0
        a, b = self.coefficients
        l2 = wavelength_um * wavelength_um
        if self.kind == "model":
            return a[0] + b[0] / l2
        n2 = 1.0
        for bi, ci in zip(a, b):
            n2 = n2 + bi * l2 / (l2 - ci)
        return sqrt(n2)

    def abbe(self) -> tuple[float, float]:
        """(n_d, V_d) computed from the dispersion formula."""
        nd, nf, nc = (float(self.index(w)) for w in (LINE_D, LINE_F, LINE_C))
        return nd, (nd - 1.0) / (nf - nc)


AIR = Glass("AIR", "air")


def model_glass(nd: float, vd: float | None = None) -> Glass:
    """Model glass with exactly the given n_d and V_d: n(λ) = A + B/λ² (Cauchy's two terms); without
    V_d, the constant index n_d (no dispersion)."""
    if vd is None:
        if not 1.0 < nd < 3.0:
            raise SolasError(f"model glass n_d={nd:g}: n_d must lie in (1, 3)")
        return Glass(f"model:{nd:g}", "model", ((nd,), (0.0,)), MODEL_RANGE_NM)
    if not (1.0 < nd < 3.0) or not (5.0 < vd < 150.0):
        raise SolasError(f"model glass n_d={nd:g}, V_d={vd:g}: n_d must lie in (1, 3) and V_d in (5, 150)")
    inv = lambda nm: 1.0 / (nm / 1000.0) ** 2  # noqa: E731 - µm⁻²
    b = (nd - 1.0) / vd / (inv(LINE_F) - inv(LINE_C))
    a = nd - b * inv(LINE_D)
    return Glass(f"model:{nd:g}/{vd:g}", "model", ((a,), (b,)), MODEL_RANGE_NM)


@lru_cache(maxsize=4)
def _entries(path: str | None) -> dict:
    """The catalogue file's [glass] tables."""
    with open(path or CATALOG_PATH, "rb") as f:
        return tomllib.load(f)["glass"]


@lru_cache(maxsize=4)
def load_catalog(path: str | None = None) -> dict[str, Glass]:
    """The catalogue as {"VENDOR:NAME": Glass}."""
    entries = _entries(path)
    return {
        key: Glass(key, "sellmeier", (tuple(e["B"]), tuple(e["C"])), tuple(e["range_nm"]))
        for key, e in entries.items()
    }


@lru_cache(maxsize=4)
def _aliases(path: str | None = None) -> dict[str, list[str]]:
    """Upper-case name → catalogue keys it may mean (full key, bare name and listed aliases)."""
    names: dict[str, list[str]] = {}
    for key, e in _entries(path).items():
        for name in {key, key.split(":", 1)[-1], *e.get("aliases", [])}:
            names.setdefault(name.upper(), []).append(key)
    return names


def resolve(name: str, catalog: str | None = None) -> Glass:
    """The one glass that `name` means: "AIR", a catalogue name ("N-BK7", "SCHOTT:F2", "BK7"),
    "model:n_d/V_d" or "model:n_d". Unknown or ambiguous names raise SolasError."""
    if not isinstance(name, str) or not name.strip():
        raise SolasError(f"glass name {name!r} must be a non-empty string")
    if name.strip().upper() == "AIR":
        return AIR
    m = _MODEL_RE.match(name)
    if m:
        return model_glass(float(m.group(1)), None if m.group(2) is None else float(m.group(2)))
    keys = _aliases(catalog).get(name.strip().upper(), [])
    if not keys:
        known = sorted({k.split(":", 1)[-1] for k in load_catalog(catalog)})
        raise SolasError(
            f"unknown glass {name!r}; known: AIR, {', '.join(known)}, or model:n_d/V_d (e.g. model:1.62/36.4)"
        )
    if len(set(keys)) > 1:
        raise SolasError(f"glass name {name!r} is ambiguous: it matches {', '.join(sorted(set(keys)))}; use one of those")
    return load_catalog(catalog)[keys[0]]


@lru_cache(maxsize=4)
def _abbe_table(path: str | None = None) -> tuple[tuple[str, float, float], ...]:
    """(key, n_d, V_d) of every catalogue glass, from its formula."""
    return tuple((key, *g.abbe()) for key, g in load_catalog(path).items())


def material_for(nd: float, vd: float | None, catalog: str | None = None) -> str:
    """The material name for a lens table's n_d (and V_d, None when not given): "AIR" for n_d ≤ 1, the
    catalogue glass nearest in n_d within MATCH_ND and in V_d within MATCH_VD, else a model glass
    ("model:n_d/V_d", or the constant index "model:n_d" without V_d). n_d is rounded to 1e-7 and V_d to
    1e-5 first: tables print them so, and the written name stays short."""
    if nd <= 1.0:
        return "AIR"
    nd = round(nd, 7)
    if vd is None:
        return f"model:{nd!r}"
    vd = round(vd, 5)
    near = [(abs(n - nd), key) for key, n, v in _abbe_table(catalog)
            if abs(n - nd) <= MATCH_ND and abs(v - vd) <= MATCH_VD]
    return min(near)[1] if near else f"model:{nd!r}/{vd!r}"
