"""A lens's tolerances: a tolerance file (TOML, `read_spec`), each tolerance's perturbation of a
lens (`perturbed`, through `dataclasses.replace` of the public `Lens` and `Surface`), and the lenses of a
Monte Carlo drawn from it (`draw`), each sample's random stream derived from the seed and the sample's
index alone (`numpy.random.default_rng([seed, index])`), so a sample is the same lens whichever worker
draws it and however many there are.

A tolerance file::

    test_wavelength_nm = 632.8          # the fringes' wavelength (default: a HeNe test interferometer)
    [compensator]
    back_focus = "rms-spot"             # "rms-spot" (default), "mtf50" or "none" (analysis.tolerance)
    [[tolerance]]
    kind = "radius"                     # `KINDS`
    surfaces = [1, 2]                   # 1-based, or "all" (every surface the kind applies to)
    fringes = 2.0                       # the kind's unit: one of `KINDS[kind].units`
    distribution = "normal"             # normal: the value is σ, draws beyond ±truncate·σ drawn again
    truncate = 2.0                      # (σ; default 3); uniform: the value is the limit ±value

What each kind moves (lengths in mm):
- radius: percent of R, or fringes N of power at `test_wavelength_nm` over the clear aperture: the sag
  at the semi-diameter y changes by N λ/2 (one fringe of a test plate in reflection) toward the centre of
  curvature's side (+z for a flat surface), c' = 2 s'/(y² + s'²) for the sphere through that sag.
- thickness: mm added to a surface's thickness (glass or air gap; not the last: that is `despace`).
- index, abbe: the glass after the surface melted off its catalogue values (`melt`): Δn_d, ΔV_d (or
  percent of V_d); the dispersion curve is scaled so the partial dispersions hold.
- irregularity: a rotationally symmetric irregularity, fringes N of a fourth-order sag term
  h (r/y)⁴, h = N λ/2 at the semi-diameter y, toward the centre of curvature as for radius (the even-
  asphere term A4 += ±h/y⁴): the vertex curvature stays, the zone departs.
- despace: mm added to the image distance: the sensor's axial error, after the back-focus compensator
  where there is one (`analysis.tolerance`: it focuses, then the sensor sits this far from that focus).
- decentre: mm, an element (`surfaces`: its consecutive surfaces) decentred along x and along y, two terms
  drawn independently ("decentre_x s3-4", "decentre_y s3-4"); tilt: degrees about x and about y, about the
  element's first vertex as Zemax's TETX/TETY; sensor_tilt: degrees about x and y, about the sensor's axial
  point (no surfaces). The drawn lens is a lens as built (`tolerance_placement`: coordinate breaks).
Non-symmetric irregularity (`REFUSED`) is refused by name.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import SolasError
from ..userfiles import read_toml
from . import glass as glass_mod
from . import lens_checks, thermal
from . import tolerance_placement as as_built

DEFAULT_TEST_WAVELENGTH_NM = 632.8  # HeNe: the wavelength fringes are counted at unless the file says
DEFAULT_TRUNCATE = 3.0  # σ: a normal draw beyond ±3σ is drawn again
DISTRIBUTIONS = ("normal", "uniform")
COMPENSATORS = ("rms-spot", "mtf50", "none")
SIDES = ((-1.0, "minus"), (1.0, "plus"))  # a sensitivity's two draws: −1 and +1 σ (or ± the limit)
LENS_FOLDER = "lenses"  # where `solas-mi tolerance` writes its drawn lenses (a population a batch reads)
MAX_TERMS = 1000  # tolerances × surfaces of one file
REFUSED = {
    "irregularity_astigmatism": "an astigmatic (non-symmetric) irregularity",
}
SPEC_KEYS = ("test_wavelength_nm", "compensator", "tolerance")
ENTRY_KEYS = ("kind", "surfaces", "distribution", "truncate")


@dataclass(frozen=True)
class Kind:
    """A kind of tolerance: its units (the first is what a term's delta is in after reading), what it
    moves, and which surfaces it may apply to (`applies(lens, i)`: None, or why not)."""

    units: tuple[str, ...]
    meaning: str
    per_surface: bool = True


KINDS = {
    "radius": Kind(("fringes", "percent"), "a surface's radius"),
    "thickness": Kind(("mm",), "a surface's thickness (glass or air gap)"),
    "index": Kind(("delta",), "the glass's n_d (melt)"),
    "abbe": Kind(("delta", "percent"), "the glass's V_d (melt)"),
    "irregularity": Kind(("fringes",), "a fourth-order symmetric sag term"),
    "despace": Kind(("mm",), "the sensor's axial position", per_surface=False),
    "decentre": Kind(("mm",), "an element's decentre in x and y (its surfaces as a group)"),
    "tilt": Kind(("degrees",), "an element's tilt about x and y (about its first vertex)"),
    "sensor_tilt": Kind(("degrees",), "the sensor's tilt about x and y", per_surface=False),
}


@dataclass(frozen=True)
class Term:
    """One tolerance on one surface (0-based `surface`; None for the sensor): its kind, unit, the value
    (σ of a normal, the limit of a uniform) and distribution."""

    kind: str
    surface: int | None
    unit: str
    value: float
    distribution: str = "normal"
    truncate: float = DEFAULT_TRUNCATE
    axis: str = ""  # an as-built kind's x or y (`tolerance_placement.AXES`)
    last: int | None = None  # an element's last surface (0-based; decentre, tilt)

    @property
    def name(self) -> str:
        """ "radius s2", "despace", "tilt_x s3-4", "sensor_tilt_y": how columns and tables name it."""
        kind = f"{self.kind}_{self.axis}" if self.axis else self.kind
        if self.surface is None:
            return kind
        end = f"-{self.last + 1}" if self.last is not None and self.last != self.surface else ""
        return f"{kind} s{self.surface + 1}{end}"

    def draw(self, rng: np.random.Generator) -> float:
        """One draw of this term's delta (in `unit`) from `rng`."""
        if self.distribution == "uniform":
            return float(rng.uniform(-self.value, self.value))
        while True:
            z = float(rng.standard_normal())
            if abs(z) <= self.truncate:
                return z * self.value


@dataclass(frozen=True)
class ToleranceSpec:
    """A tolerance file read: its terms (one per tolerance and surface), the fringes' wavelength and the
    back-focus compensator."""

    terms: tuple[Term, ...]
    test_wavelength_nm: float = DEFAULT_TEST_WAVELENGTH_NM
    compensator: str = "rms-spot"


def _number(entry: dict, key: str, where: str) -> float:
    """entry[key], a positive finite number, or SolasError naming it."""
    value = entry[key]
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value) or value <= 0:
        raise SolasError(f"{where}: {key} = {value!r} must be a positive number")
    return float(value)


def _why_not(lens, kind: str, i: int, unit: str) -> str | None:
    """Why tolerance `kind` (in `unit`) cannot apply to surface `i` (0-based) of `lens`; None when it can."""
    s = lens.surfaces[i]
    if kind in ("radius", "irregularity") and s.ideal:
        return "an ideal thin lens has no shape"
    if kind == "radius" and unit == "percent" and s.radius == 0:
        return "a flat surface has no radius to take a percent of (give fringes)"
    if kind == "thickness" and i == len(lens.surfaces) - 1:
        return 'the last thickness is the image distance (kind = "despace")'
    if kind in ("index", "abbe") and s.glass.kind not in ("sellmeier", "polynomial", "conrady", "model"):
        return f"its medium {s.glass.name} is {'air' if s.glass.kind == 'air' else 'a table of indices'}"
    if kind == "abbe" and not s.glass.dispersive:
        return f"its medium {s.glass.name} has no dispersion"
    return None


def _surfaces(lens, entry: dict, kind: str, unit: str, where: str) -> list[int | None]:
    """The 0-based surfaces of an entry ("all": each the kind applies to), each checked."""
    if not KINDS[kind].per_surface:
        if "surfaces" in entry:
            raise SolasError(f"{where}: kind {kind!r} takes no surfaces (it moves {KINDS[kind].meaning})")
        return [None]
    value = entry.get("surfaces")
    count = len(lens.surfaces)
    element = f"{where}: surfaces = {value!r} must be an element's consecutive surface numbers, e.g. [3, 4]"
    if value == "all" and kind in as_built.AS_BUILT:
        raise SolasError(element)
    if value == "all":
        return [i for i in range(count) if _why_not(lens, kind, i, unit) is None]
    if (
        not isinstance(value, list)
        or not value
        or not all(isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= count for v in value)
    ):
        raise SolasError(f'{where}: surfaces = {value!r} must be "all" or a list of surface numbers from 1 to {count}')
    if kind in as_built.AS_BUILT and value != list(range(value[0], value[0] + len(value))):
        raise SolasError(element)
    for v in value:
        why = _why_not(lens, kind, v - 1, unit)
        if why:
            raise SolasError(f"{where}: {kind} on surface {v} ({lens.surfaces[v - 1].label}): {why}")
    return [v - 1 for v in dict.fromkeys(value)]


def _entry_terms(lens, entry, n: int) -> list[Term]:
    """The terms of [[tolerance]] entry `n` (1-based), checked."""
    where = f"tolerance {n}"
    if not isinstance(entry, dict):
        raise SolasError(f"{where}: {entry!r} must be a table ([[tolerance]] with kind, surfaces, a value)")
    kind = entry.get("kind")
    if kind in REFUSED:
        raise SolasError(
            f"{where}: kind {kind!r} ({REFUSED[kind]}) is not supported yet: it needs surfaces with their own frame "
            f"(the lens as built); allowed: {', '.join(KINDS)}"
        )
    if kind not in KINDS:
        raise SolasError(f"{where}: kind = {kind!r}; allowed: {', '.join(KINDS)}")
    where = f"{where} ({kind})"
    units = KINDS[kind].units
    unknown = sorted(set(entry) - set(ENTRY_KEYS) - set(units))
    given = [u for u in units if u in entry]
    if unknown or len(given) != 1:
        raise SolasError(
            f"{where}: {'unknown keys ' + ', '.join(unknown) if unknown else 'give exactly one value'}; "
            f"allowed: {', '.join(ENTRY_KEYS)} and one of {', '.join(units)}"
        )
    distribution = entry.get("distribution", "normal")
    if distribution not in DISTRIBUTIONS:
        raise SolasError(f"{where}: distribution = {distribution!r}; allowed: {', '.join(DISTRIBUTIONS)}")
    if "truncate" in entry and distribution != "normal":
        raise SolasError(f"{where}: truncate (in σ) is for the normal distribution only")
    truncate = _number(entry, "truncate", where) if "truncate" in entry else DEFAULT_TRUNCATE
    value = _number(entry, given[0], where)
    surfaces = _surfaces(lens, entry, kind, given[0], where)
    if kind in as_built.AS_BUILT:
        first, last = (None, None) if surfaces == [None] else (surfaces[0], surfaces[-1])
        return [Term(kind, first, given[0], value, distribution, truncate, axis, last) for axis in as_built.AXES]
    return [Term(kind, i, given[0], value, distribution, truncate) for i in surfaces]


def read_spec(lens, path) -> ToleranceSpec:
    """The tolerance file at `path` (module docstring) for `lens`, checked; SolasError naming the bad entry."""
    return spec_from_dict(lens, read_toml(path, "tolerance file"), f"tolerance file {str(path)!r}")


def spec_from_dict(lens, table: dict, where: str = "tolerances") -> ToleranceSpec:
    """A tolerance file's table (module docstring) for `lens` as a `ToleranceSpec`, checked."""
    unknown = sorted(set(table) - set(SPEC_KEYS))
    if unknown:
        raise SolasError(f"{where}: unknown keys {', '.join(unknown)}; allowed: {', '.join(SPEC_KEYS)}")
    wavelength = _number(table, "test_wavelength_nm", where) if "test_wavelength_nm" in table else None
    compensator = table.get("compensator", {})
    if not isinstance(compensator, dict) or set(compensator) - {"back_focus"}:
        raise SolasError(f"{where}: [compensator] may hold back_focus only ({', '.join(COMPENSATORS)})")
    back_focus = compensator.get("back_focus", COMPENSATORS[0])
    if back_focus not in COMPENSATORS:
        raise SolasError(f"{where}: compensator back_focus = {back_focus!r}; allowed: {', '.join(COMPENSATORS)}")
    entries = table.get("tolerance")
    if not isinstance(entries, list) or not entries:
        raise SolasError(f"{where}: no [[tolerance]] entries (each: kind, surfaces, a value, distribution)")
    terms = [t for n, entry in enumerate(entries, start=1) for t in _entry_terms(lens, entry, n)]
    names = [t.name for t in terms]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice or len(terms) > MAX_TERMS:
        raise SolasError(
            f"{where}: {'tolerances given twice: ' + ', '.join(twice) if twice else 'too many terms'}"
            f" (each kind at most once per surface, at most {MAX_TERMS} in all)"
        )
    groups = sorted({(t.surface or 0, t.last) for t in terms if t.last is not None})
    for (a, b), (c, d) in itertools.pairwise(groups):
        if c <= b:
            raise SolasError(f"{where}: elements s{a + 1}-{b + 1} and s{c + 1}-{d + 1} share surfaces (give each once)")
    return ToleranceSpec(tuple(terms), wavelength or DEFAULT_TEST_WAVELENGTH_NM, back_focus)


def _fringe_radius(surface, fringes: float, wavelength_mm: float) -> float:
    """The radius whose sag at the semi-diameter differs from `surface`'s by `fringes` λ/2 (module docstring)."""
    y, c = surface.semi_diameter, surface.curvature
    sag = c * y * y / (1.0 + math.sqrt(max(1.0 - c * c * y * y, 0.0)))
    new = sag + 0.5 * fringes * wavelength_mm * (-1.0 if c < 0 else 1.0)
    curvature = 2.0 * new / (y * y + new * new)
    return 0.0 if curvature == 0 else 1.0 / curvature


def _melted(g, delta_nd: float, delta_vd: float):
    """Glass `g` melted by (Δn_d, ΔV_d) (`melt`), named for it: a model glass by its new n_d / V_d."""
    if g.kind == "model":
        nd, vd = g.abbe() if g.dispersive else (g.index(glass_mod.LINE_D), None)
        name = glass_mod.model_name(nd + delta_nd, None if vd is None else vd + delta_vd)
        return glass_mod.resolve(name).at(*(g.environment or (thermal.STANDARD_C, thermal.STANDARD_KPA))), name
    name = f"{g.name} melt {delta_nd!r}/{delta_vd!r}"
    return replace(g, name=name, melt=(delta_nd, delta_vd), nd=None, vd=None), name


def perturbed(lens, spec: ToleranceSpec, deltas):
    """`lens` with each of `spec.terms` moved by its delta in `deltas` (one per term, in the term's unit; 0:
    untouched), named the lens's own; its glasses melted become the lens's own materials."""
    surfaces = list(lens.surfaces)
    melts: dict[int, list[float]] = {}
    wavelength_mm = spec.test_wavelength_nm * 1e-6
    for term, delta in zip(spec.terms, deltas):
        if not delta or term.kind in as_built.AS_BUILT:
            continue
        i = len(surfaces) - 1 if term.surface is None else term.surface
        s = surfaces[i]
        if term.kind == "radius":
            radius = (
                s.radius * (1.0 + delta / 100.0) if term.unit == "percent" else _fringe_radius(s, delta, wavelength_mm)
            )
            surfaces[i] = replace(s, radius=radius)
        elif term.kind in ("thickness", "despace"):
            surfaces[i] = replace(s, thickness=s.thickness + delta)
        elif term.kind == "irregularity":
            a4 = 0.5 * delta * wavelength_mm / s.semi_diameter**4 * (-1.0 if s.curvature < 0 else 1.0)
            surfaces[i] = replace(s, aspheric=(((s.aspheric or (0.0,))[0] + a4), *s.aspheric[1:]))
        else:
            melt = melts.setdefault(i, [0.0, 0.0])
            vd = s.glass.abbe()[1] if term.kind == "abbe" and term.unit == "percent" else None
            melt[term.kind == "abbe"] += delta if vd is None else vd * delta / 100.0
    materials = list(lens.materials)
    for i, (dn, dv) in sorted(melts.items()):
        g, name = _melted(surfaces[i].glass, dn, dv)
        surfaces[i] = replace(surfaces[i], glass=g, material=name)
        materials += [g] if g.kind != "model" else []
    lens = replace(lens, surfaces=tuple(surfaces), materials=tuple(materials))
    groups, sensor = as_built.moves(spec, deltas)
    return as_built.placed(lens, groups, sensor) if groups or any(sensor) else lens


def symmetric(lens, spec: ToleranceSpec, deltas):
    """`perturbed` by `deltas` without the as-built terms: the drawn lens's part on one axis."""
    return perturbed(lens, spec, [0.0 if t.kind in as_built.AS_BUILT else d for t, d in zip(spec.terms, deltas)])


def parameter(lens, term: Term) -> float:
    """What `term` moves, as `lens` has it: a radius or thickness (the image distance for despace, mm), the
    A4 term (irregularity, mm⁻³), the glass's n_d or V_d (index, abbe)."""
    if term.kind in as_built.AS_BUILT:
        return as_built.parameter(lens, term)
    s = lens.surfaces[-1 if term.surface is None else term.surface]
    if term.kind in ("index", "abbe"):
        return s.glass.abbe()[term.kind == "abbe"]
    if term.kind == "irregularity":
        return (s.aspheric or (0.0,))[0]
    return s.radius if term.kind == "radius" else s.thickness


def despace(spec: ToleranceSpec, deltas) -> float:
    """The sensor's despace (mm) among `deltas` (0 where the file has none)."""
    return sum(d for term, d in zip(spec.terms, deltas) if term.kind == "despace")


def alone(lens, spec: ToleranceSpec, k: int, sign: float):
    """`lens` with term `k` of `spec` alone at `sign` (±1) times its σ (normal) or its limit (uniform)."""
    deltas = [0.0] * len(spec.terms)
    deltas[k] = sign * spec.terms[k].value
    return perturbed(lens, spec, deltas)


def paraxial_sensitivity(lens, spec: ToleranceSpec) -> list[dict]:
    """Each term alone at −1 and +1 (`alone`): the parameter it moves and the EFL (primary wavelength) at
    both, and dEFL/dparameter, their central difference."""
    from .paraxial import paraxial

    rows = []
    for k, term in enumerate(spec.terms):
        row: dict = {"term": term.name, "unit": term.unit, "delta": term.value}
        for sign, side in SIDES:
            moved = alone(lens, spec, k, sign)
            row[f"parameter_{side}"] = parameter(moved, term)
            row[f"efl_mm_{side}"] = paraxial(moved, moved.primary_wavelength).efl_mm
        step = row["parameter_plus"] - row["parameter_minus"]
        row["defl_dparameter"] = (row["efl_mm_plus"] - row["efl_mm_minus"]) / step if step else math.nan
        rows.append(row)
    return rows


def draw_deltas(spec: ToleranceSpec, seed: int, index: int) -> list[float]:
    """The deltas of sample `index` of the Monte Carlo of seed `seed`: its own stream, the terms in order."""
    rng = np.random.default_rng([seed, index])
    return [term.draw(rng) for term in spec.terms]


def draw(lens, spec: ToleranceSpec, seed: int, index: int):
    """(lens of sample `index`, its deltas): `perturbed` by `draw_deltas`, named `<lens> sample <index>`;
    SolasError where the draw cannot be built (a lens file's checks, `lens_checks`, or faces that cross
    where the design's do not), naming the sample: its tolerances are too wide for the lens."""
    deltas = draw_deltas(spec, seed, index)
    drawn = perturbed(lens, spec, deltas)
    drawn = replace(drawn, name=f"{lens.name} sample {index}", description=f"{lens.name} drawn by seed {seed}")
    where = f"tolerance sample {index} of seed {seed}"
    lens_checks.validate(drawn, where)
    crossing = [note for note in drawn.overlaps if note not in lens.overlaps]
    if len(drawn.overlaps) > len(lens.overlaps):
        raise SolasError(
            f"{where}: {crossing[0] if crossing else drawn.overlaps[0]}; the tolerances draw lenses "
            "that cannot be built (give smaller values, or truncate the normal ones)"
        )
    return drawn, deltas


__all__ = [
    "COMPENSATORS",
    "DISTRIBUTIONS",
    "KINDS",
    "LENS_FOLDER",
    "REFUSED",
    "Term",
    "ToleranceSpec",
    "draw",
    "draw_deltas",
    "SIDES",
    "alone",
    "despace",
    "parameter",
    "paraxial_sensitivity",
    "perturbed",
    "read_spec",
    "spec_from_dict",
    "symmetric",
]
