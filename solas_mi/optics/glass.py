"""Optical glass: the catalogue (Sellmeier) and model glass given by (n_d, V_d).

Indices are relative to air; AIR has index 1. Wavelengths are in nm.

The catalogue: one TOML file per vendor (`data/glass_<vendor>.toml`: SCHOTT, OHARA, HOYA, CDGM, SUMITA,
HIKARI; CORNING; the moulders LIGHTPATH and RPO; the optical plastics of ZEON, OSAKAGASCHEMICAL and
ANGSTROMLINK; and MISC for materials of no vendor, such as fused silica and PMMA), numbers from the
refractiveindex.info database (public domain), which took them from the vendors' Zemax catalogues or the
literature, or from OpticStudio's catalogues of those names (their formulas, ranges and n_d / V_d); each
file's header says which and when (an entry marked `fitted` is our fit to a data sheet's table of
indices). Entries are named "VENDOR:NAME"; a bare name (or an alias such as "BK7") must mean exactly one
entry; an entry marked `by_name` (SCHOTT's obsolete LAK33, ... from OpticStudio's catalogue) answers to its
bare name only where no other entry has it, and never to a table's n_d / V_d. Loaded on first use and cached.

References: the Sellmeier formula n² = 1 + Σ B λ²/(λ² − C) and the power series n² = Σ K λ^P (the
Schott / Hoya / Sumita / Hikari formulas, refractiveindex.info's "formula 3") with the vendors' valid
ranges (SCHOTT TIE-29 "Refractive Index and Dispersion"); model glass from n_d and V_d (Fraunhofer
d, F, C lines) as a two-term Cauchy fit.
"""
from __future__ import annotations

import difflib
import itertools
import re
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..caches import parsed_files
from ..errors import SolasError
from . import melt as melt_mod
from . import thermal

CATALOG_DIR = Path(__file__).parent / "data"
# The vendors' catalogue files, read in this order (the order names no preference).
VENDORS = ("SCHOTT", "OHARA", "HOYA", "CDGM", "SUMITA", "HIKARI", "CORNING", "LIGHTPATH", "RPO", "ZEON",
           "OSAKAGASCHEMICAL", "ANGSTROMLINK", "MISC")
# Fraunhofer lines (nm) defining n_d and V_d.
LINE_D, LINE_F, LINE_C = 587.5618, 486.1327, 656.2725
# Range (nm) over which a model glass's two-term dispersion is offered.
MODEL_RANGE_NM = (365.0, 1014.0)
# A constant index (a model medium without dispersion, relative to air) holds at every wavelength; below 1
# are media thinner than air (vacuum 0.99973, helium, as a lithography lens's purge gas).
CONSTANT_RANGE = (0.9, 3.0)
_NUMBER = r"([0-9]+(?:\.[0-9]*)?|\.[0-9]+)"
_MODEL_RE = re.compile(rf"^\s*model\s*:\s*{_NUMBER}\s*(?:/\s*{_NUMBER}\s*)?$", re.IGNORECASE)
# A catalogue glass stands for a table's (n_d, V_d) when both agree within these (its formula's values).
MATCH_ND, MATCH_VD = 5e-5, 0.05


@dataclass(frozen=True)
class Glass:
    """A refractive medium. `kind` is "sellmeier" (coefficients (B, C)), "polynomial" (coefficients
    (K, P): n² = Σ K λ^P, P even integers), "conrady" (coefficients ((A0, A1, A2), ()): n = A0 + A1/λ +
    A2/λ^3.5, the Zemax AGF's formula 5), "table" (coefficients (wavelengths in nm, increasing, and
    indices): a lens file's own material, a natural cubic spline in 1/λ² through its points), "model" or "air". `nd`, `vd`: a
    catalogue glass's stated values (None for others). `thermal`: the Schott formula's (D0, D1, D2, E0, E1,
    λ_TK µm) about `reference_c` (°C), `cte`: the linear expansion (1/K, −30 … +70 °C), () and None where the
    catalogue has none; `environment`: (°C, kPa) of the air around it where not 20 °C and 101.325 kPa
    (`at`, `thermal`)."""

    name: str
    kind: str
    coefficients: tuple[tuple[float, ...], tuple[float, ...]] = ((), ())
    range_nm: tuple[float, float] = (0.0, float("inf"))
    nd: float | None = None
    vd: float | None = None
    thermal: tuple[float, ...] = ()
    reference_c: float = 20.0
    cte: float | None = None
    environment: tuple[float, float] | None = None
    melt: tuple[float, ...] = ()  # (Δn_d, ΔV_d): a melt off the catalogue's values (`melt`); (): the catalogue's

    def at(self, temperature_c: float, pressure_kpa: float) -> Glass:
        """This glass at `temperature_c` in air of `pressure_kpa`, its index relative to that air (`thermal`):
        itself (environment None) at 20 °C and 101.325 kPa, and air is always air."""
        standard = (temperature_c, pressure_kpa) == (thermal.STANDARD_C, thermal.STANDARD_KPA)
        if self.kind == "air" or (standard and self.environment is None):
            return self
        return replace(self, environment=None if standard else (float(temperature_c), float(pressure_kpa)))

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
        n = np.asarray(self.index_formula(wl / 1000.0, np.sqrt))
        return float(n) if n.ndim == 0 else n

    def index_formula(self, wavelength_um, sqrt: Callable, select: Callable = np.where, constant: Callable = float):
        """n(λ) with λ in µm for any array type (NumPy, Dr.Jit) given its `sqrt` and `select(mask, a, b)`
        (a table's spline picks its piece); no range check. At an `environment`, relative to its air. `constant`
        makes each number of the glass (coefficients, a melt's terms, thermal data, environment) a value of the
        caller's type: the Dr.Jit tracer's opaque kernel inputs, so a melt or another glass reuses its kernels."""
        n = self._catalogue_index(wavelength_um, sqrt, select, constant)
        # a melt's n_d and V_d (`melt`); the catalogue's glass too (0, 1: n itself), so a melt runs its kernels
        offset, scale = melt_mod.terms(self) if self.melt else (0.0, 1.0)
        n = constant(offset) + constant(scale) * n
        return n if self.environment is None else thermal.relative_index(self, n, wavelength_um, self.environment, constant)

    def _catalogue_index(self, wavelength_um, sqrt: Callable, select: Callable, constant: Callable = float):
        """n(λ) of the formula (at 20 °C in standard air), λ in µm; `constant` as `index_formula`'s."""
        if self.kind == "air":
            return wavelength_um * 0.0 + 1.0
        a, b = self.coefficients
        l2 = wavelength_um * wavelength_um
        if self.kind == "model":
            return constant(a[0]) + constant(b[0]) / l2
        if self.kind == "conrady":
            a0, a1, a2 = (constant(v) for v in a)
            return a0 + a1 / wavelength_um + a2 / (l2 * wavelength_um * sqrt(wavelength_um))
        if self.kind == "table":
            return _spline(a, b, wavelength_um, select, constant)
        if self.kind == "polynomial":
            n2 = wavelength_um * 0.0
            inv = 1.0 / l2
            for k, p in zip(a, b):
                term, base = constant(k), (l2 if p > 0 else inv)
                for _ in range(abs(int(p)) // 2):
                    term = term * base
                n2 = n2 + term
            return sqrt(n2)
        n2 = 1.0
        for bi, ci in zip(a, b):
            n2 = n2 + constant(bi) * l2 / (l2 - constant(ci))
        return sqrt(n2)

    @property
    def dispersive(self) -> bool:
        """Whether the index changes with wavelength (air and a model glass of n_d alone do not)."""
        return self.kind != "air" and (self.kind != "model" or self.coefficients[1][0] != 0)

    def abbe(self) -> tuple[float, float]:
        """(n_d, V_d) computed from the dispersion formula."""
        nd, nf, nc = (float(self.index(w)) for w in (LINE_D, LINE_F, LINE_C))
        return nd, (nd - 1.0) / (nf - nc)


AIR = Glass("AIR", "air")


@lru_cache(maxsize=64)
def _pieces(wavelengths_nm: tuple[float, ...], index: tuple[float, ...]) -> tuple[tuple[float, ...], ...]:
    """The natural cubic spline through (1/λ², n) (λ µm; in 1/λ² an index is nearly straight, as Cauchy's
    formula says): per piece (x_i, n_i, slope, curvature / 2, cubic), x increasing."""
    x, y = (1000.0 / np.asarray(wavelengths_nm)) ** 2, np.asarray(index, dtype=np.float64)
    x, y = x[::-1], y[::-1]
    m, h = len(x), np.diff(x)
    second = np.zeros(m)
    if m > 2:  # the second derivatives: zero at both ends, continuous slopes inside
        system = np.diag(2.0 * (h[:-1] + h[1:])) + np.diag(h[1:-1], 1) + np.diag(h[1:-1], -1)
        second[1:-1] = np.linalg.solve(system, 6.0 * np.diff(np.diff(y) / h))
    slope = np.diff(y) / h - h * (2.0 * second[:-1] + second[1:]) / 6.0
    cubic = (second[1:] - second[:-1]) / (6.0 * h)
    return tuple(tuple(map(float, piece)) for piece in zip(x[:-1], y[:-1], slope, second[:-1] / 2.0, cubic))


def _spline(wavelengths_nm, index, wavelength_um, select: Callable, constant: Callable = float):
    """A table's index at `wavelength_um`: its spline piece's cubic (the first and last pieces reach past
    the ends; `Glass.index` keeps wavelengths within the table); `constant` as `Glass.index_formula`'s."""
    x, n = 1.0 / (wavelength_um * wavelength_um), None
    for piece in _pieces(tuple(wavelengths_nm), tuple(index)):
        x0, y0, b, c, d = (constant(v) for v in piece)
        t = x - x0
        value = y0 + t * (b + t * (c + t * d))
        n = value if n is None else select(x >= x0, value, n)
    return n


def own_material(name: str, entry: dict, where: str) -> Glass:
    """A lens file's own material `name` (its [materials] table): a table of indices (`wavelengths_nm`,
    `index`: the spline through them, offered over their span) or a formula with a catalogue entry's
    keys (B and C, K and P, or conrady; with range_nm)."""
    ident = f"{where}: material {name!r}"
    if not isinstance(entry, dict):
        raise SolasError(f"{ident} must be a table: wavelengths_nm and index, or a formula (B/C, K/P or conrady) "
                         "with range_nm")
    if "index" in entry or "wavelengths_nm" in entry:
        wl, n = entry.get("wavelengths_nm"), entry.get("index")
        good = (isinstance(wl, list) and isinstance(n, list) and len(wl) == len(n) >= 1
                and all(isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) for v in wl + n))
        if not good or any(b <= a for a, b in itertools.pairwise(wl)) or not all(w > 0 for w in wl) \
                or not all(1.0 < v < 5.0 for v in n):
            raise SolasError(f"{ident}: wavelengths_nm = {wl!r}, index = {n!r}: give lists of the same length, "
                             "wavelengths (nm) positive and increasing, indices in (1, 5)")
        if len(wl) == 1:  # one index: no dispersion
            return Glass(name, "model", ((float(n[0]),), (0.0,)), (0.0, float("inf")))
        return Glass(name, "table", (tuple(map(float, wl)), tuple(map(float, n))), (float(wl[0]), float(wl[-1])))
    try:
        g = _glass(name, entry)
        g.abbe() if g.range_nm[0] <= LINE_F and g.range_nm[1] >= LINE_C else g.index(g.range_nm[0])
    except (KeyError, TypeError, ValueError) as exc:
        raise SolasError(f"{ident}: {exc!s} is missing or wrong; give B and C (Sellmeier), K and P (power "
                         "series) or conrady (A0, A1, A2), each with range_nm = [lo, hi] (nm)") from None
    return g


def model_glass(nd: float, vd: float | None = None) -> Glass:
    """Model glass with exactly the given n_d and V_d: n(λ) = A + B/λ² (Cauchy's two terms); without
    V_d, the constant index n_d (no dispersion)."""
    if vd is None:
        if not CONSTANT_RANGE[0] < nd < CONSTANT_RANGE[1]:
            raise SolasError(f"model glass n_d={nd:g}: a constant index must lie in {CONSTANT_RANGE} (below 1: a "
                             "medium thinner than air, such as vacuum 0.99973 or helium)")
        return Glass(f"model:{nd:g}", "model", ((nd,), (0.0,)))
    if not (1.0 < nd < 3.0) or not (5.0 < vd < 150.0):
        raise SolasError(f"model glass n_d={nd:g}, V_d={vd:g}: n_d must lie in (1, 3) and V_d in (5, 150)")
    inv = lambda nm: 1.0 / (nm / 1000.0) ** 2  # noqa: E731 - µm⁻²
    b = (nd - 1.0) / vd / (inv(LINE_F) - inv(LINE_C))
    a = nd - b * inv(LINE_D)
    return Glass(f"model:{nd:g}/{vd:g}", "model", ((a,), (b,)), MODEL_RANGE_NM)


def model_name(nd: float, vd: float | None = None) -> str:
    """The material name of the model glass of `nd` and `vd` (None or 0: a constant index), as a lens
    file's reader writes it, checked as `model_glass` checks it."""
    model_glass(nd, vd or None)
    return f"model:{nd!r}" if not vd else f"model:{nd!r}/{vd!r}"


def catalog_files() -> list[Path]:
    """The shipped catalogue files, one per vendor."""
    return [CATALOG_DIR / f"glass_{v.lower()}.toml" for v in VENDORS]


@lru_cache(maxsize=4)
def _entries(path: str | None) -> dict:
    """The [glass] tables of the catalogue file `path`, or of all shipped vendor files (None; kept parsed:
    `caches.parsed_files`)."""
    files = [Path(path)] if path else catalog_files()
    parse = lambda: {k: e for file in files for k, e in tomllib.loads(file.read_text("utf-8"))["glass"].items()}  # noqa: E731
    return parse() if path else parsed_files("glass", "parsed glass catalogue", files, parse)


def _glass(key: str, e: dict) -> Glass:
    """A catalogue entry (or a lens file's own formula) as a Glass, with its thermal data where it has them."""
    heat = {"thermal": tuple(map(float, e.get("thermal", ()))), "reference_c": float(e.get("reference_c", 20.0)),
            "cte": None if e.get("cte") is None else float(e["cte"]), "melt": tuple(map(float, e.get("melt", ())))}
    if len(heat["thermal"]) not in (0, 6) or len(heat["melt"]) not in (0, 2):
        raise ValueError("thermal (D0, D1, D2, E0, E1, λ_TK) or melt (Δn_d, ΔV_d)")
    if "conrady" in e:
        kind, coefficients = "conrady", (tuple(e["conrady"]), ())
    elif "K" in e:
        kind, coefficients = "polynomial", (tuple(e["K"]), tuple(e["P"]))
    else:
        kind, coefficients = "sellmeier", (tuple(e["B"]), tuple(e["C"]))
    return Glass(key, kind, coefficients, tuple(e["range_nm"]), e.get("nd"), e.get("vd"), **heat)


@lru_cache(maxsize=4)
def load_catalog(path: str | None = None) -> dict[str, Glass]:
    """The catalogue as {"VENDOR:NAME": Glass}: the file `path`, or the shipped one (None)."""
    return {key: _glass(key, e) for key, e in _entries(path).items()}


@lru_cache(maxsize=4)
def _aliases(path: str | None = None) -> dict[str, list[str]]:
    """Upper-case name → catalogue keys it may mean (full key, bare name and listed aliases)."""
    names: dict[str, list[str]] = {}
    for key, e in _entries(path).items():
        for name in {key, key.split(":", 1)[-1], *e.get("aliases", [])}:
            names.setdefault(name.upper(), []).append(key)
    return names


@lru_cache(maxsize=4)
def _by_name(path: str | None = None) -> frozenset[str]:
    """The keys of the entries marked `by_name` (SCHOTT's obsolete glasses of OpticStudio's catalogue)."""
    return frozenset(key for key, e in _entries(path).items() if e.get("by_name"))


def _current_first(keys: list[str], catalog: str | None) -> list[str]:
    """`keys` less the `by_name` entries, unless all are: a name that a glass of the current catalogues
    has means that glass, an obsolete one only where none answers to it."""
    gone = _by_name(catalog)
    return [k for k in keys if k not in gone] or keys


def candidates(name: str, catalog: str | None = None) -> list[str]:
    """The catalogue keys that `name` (a full key, bare name or alias, any case) may mean: `by_name`
    entries (SCHOTT's obsolete ones) only where no other entry has that name."""
    return _current_first(sorted(set(_aliases(catalog).get(name.strip().upper(), []))), catalog)


def vendors(catalog: str | None = None) -> list[str]:
    """The vendors of the catalogue, sorted."""
    return sorted({k.split(":", 1)[0] for k in load_catalog(catalog)})


def resolve(name: str, catalog: str | None = None, prefer: tuple[str, ...] = (),
            own: dict[str, Glass] | None = None) -> Glass:
    """The one glass that `name` means: a lens file's own material (`own`, by name), "AIR", a catalogue
    name ("N-BK7", "SCHOTT:F2", "OHARA:S-LAH59", "BK7"), "model:n_d/V_d" or "model:n_d". A name several
    vendors use means the entry of the first vendor in `prefer` that has exactly one of that name.
    Unknown or ambiguous names raise SolasError (an ambiguous one lists the entries it may mean)."""
    if not isinstance(name, str) or not name.strip():
        raise SolasError(f"glass name {name!r} must be a non-empty string")
    if own and name in own:
        return own[name]
    if name.strip().upper() == "AIR":
        return AIR
    m = _MODEL_RE.match(name)
    if m:
        return model_glass(float(m.group(1)), None if m.group(2) is None else float(m.group(2)))
    if re.match(r"\s*model\s*:", name, re.IGNORECASE):  # a model glass whose numbers do not read (nan, text)
        raise SolasError(f"model glass {name!r} must read model:n_d/V_d or model:n_d with finite numbers, n_d in "
                         f"(1, 3) and V_d in (5, 150), or a constant n_d in {CONSTANT_RANGE} (e.g. model:1.62/36.4)")
    keys = candidates(name, catalog)
    if not keys:
        names = _aliases(catalog)
        close = difflib.get_close_matches(name.strip().upper(), names, n=5, cutoff=0.8)
        hint = f"; close: {', '.join(sorted({k for c in close for k in names[c]}))}" if close else ""
        raise SolasError(
            f"unknown glass {name!r}{hint}; allowed: AIR, a catalogue glass ({len(load_catalog(catalog))} of "
            f"{', '.join(vendors(catalog))}, as VENDOR:NAME or a name that only one of them uses), or model:n_d/V_d "
            "(e.g. model:1.62/36.4)"
        )
    for vendor in prefer if len(keys) > 1 else ():
        mine = [k for k in keys if k.split(":", 1)[0] == vendor]
        if len(mine) == 1:
            keys = mine
            break
    if len(keys) > 1:
        raise SolasError(f"glass name {name!r} is ambiguous: it matches {', '.join(keys)}; use one of those")
    return load_catalog(catalog)[keys[0]]


@lru_cache(maxsize=4)
def _abbe_table(path: str | None = None) -> tuple[tuple[str, float, float], ...]:
    """(key, n_d, V_d) of every catalogue glass, from its formula."""
    return tuple((key, *g.abbe()) for key, g in load_catalog(path).items())


class Match(NamedTuple):
    """A catalogue glass near a wanted (n_d, V_d): its key, its stated n_d / V_d (the vendor's), and
    the n_d / V_d its formula gives."""

    key: str
    nd: float
    vd: float
    formula_nd: float
    formula_vd: float


def match(nd: float, vd: float, nd_tol: float = MATCH_ND, vd_tol: float = MATCH_VD,
          catalog: str | None = None) -> list[Match]:
    """The catalogue glasses within `nd_tol` in n_d and `vd_tol` in V_d of the given ones, by their stated
    values (the vendor's catalogue numbers, which patents quote) or by their formula's, best first: by
    the larger of |Δn_d|/nd_tol and |ΔV_d|/vd_tol (the smaller of the stated and formula scores), then
    the formula's score, then the key. Entries marked `by_name` (glasses that only a lens file naming them
    should get, such as SCHOTT's obsolete ones) are left out."""
    catalogue, entries = load_catalog(catalog), _entries(catalog)
    found = []
    for key, n, v in _abbe_table(catalog):
        g = catalogue[key]
        if entries[key].get("by_name"):
            continue
        sn, sv = (n if g.nd is None else g.nd), (v if g.vd is None else g.vd)
        stated = max(abs(sn - nd) / nd_tol, abs(sv - vd) / vd_tol)
        formula = max(abs(n - nd) / nd_tol, abs(v - vd) / vd_tol)
        if min(stated, formula) <= 1.0:
            found.append((min(stated, formula), formula, key, Match(key, sn, sv, n, v)))
    return [f[-1] for f in sorted(found)]


def _same_glass(keys: list[str], catalog: str | None) -> bool:
    """Whether the entries have the same index at the F, d and C lines to 1e-6 (one melt sold under
    several names, e.g. SCHOTT's N-SF57 and N-SF57HT)."""
    cat = load_catalog(catalog)
    n = [[float(cat[k].index(w)) for w in (LINE_F, LINE_D, LINE_C)] for k in keys]
    return all(abs(a - b) <= 1e-6 for row in n[1:] for a, b in zip(row, n[0]))


def material_for(nd: float, vd: float | None, catalog: str | None = None, nd_tol: float = MATCH_ND,
                 vd_tol: float = MATCH_VD) -> str:
    """The material name for a lens table's n_d (and V_d, None when not given): "AIR" for n_d ≤ 1; the
    catalogue glass within `nd_tol` and `vd_tol` (`match`; a table reader passes half a unit of the last
    printed digit) when it is the only one, or when all that match are one glass under several names
    (then the best-matching name); else a model glass ("model:n_d/V_d", or the constant index "model:n_d"
    without V_d): n_d / V_d that several glasses share within the table's rounding do not say which one
    was meant. n_d is rounded to 1e-7 and V_d to 1e-5 first: tables print them so, and the written name
    stays short."""
    if nd <= 1.0:
        return "AIR"
    if vd is None:
        return f"model:{round(nd, 7)!r}"
    near = [m.key for m in match(nd, vd, max(nd_tol, 1e-9), max(vd_tol, 1e-7), catalog)]
    if near and _same_glass(near, catalog):
        return near[0]
    return f"model:{round(nd, 7)!r}/{round(vd, 5)!r}"
