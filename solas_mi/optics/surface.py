"""One sequential surface of a lens (`Surface`) and the checks of a lens file's tables: the keys each
table may hold (`KEYS`), numbers, and a [[surface]] row made into a `Surface` (`surface_from_row`), every
mistake a SolasError naming the surface and what is allowed. `lens.Lens.from_dict` builds a lens of them.

A surface is a sphere, or an even asphere: sag z(r) = c r² / (1 + √(1 − (1 + k) c² r²)) + Σ_i A_2i r^2i
(i ≥ 2) with c = 1/radius, k = `conic` and `aspheric` = [A4, A6, …] (mm^(1−2i)), plus Forbes' Qbfs
departure φ u²(1 − u²) Σ a_m Q_m^bfs(u²) with `qbfs` = [a0, a1, …] (mm) and u = r / `norm_radius`
(`forbes`). A flat surface with `focal_length` (mm) is an ideal thin lens (`ideal`); `coating`, its thin
films (`coating`); the stop's `blades` (N ≥ 3) and `blade_rotation` (degrees): an iris, the regular N-gon
whose corners lie on the stop's clear circle, its sides straight or, with `blade_curvature` κ in (0, 1], arcs of
radius (clear radius)/κ bulging outward through the same corners (κ = 1: the clear circle). A surface
without rotational symmetry names its `kind` (one of `shapes.NAMED`) with that kind's entries, and is held
whole as `form`; a coordinate break before a surface (decentres, tilts: `placement`) is its `placement`.
Every shape is a geometry object of `shapes.KINDS` (`Surface.geometry`). Lengths in mm.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..errors import SolasError
from . import forbes, shapes, thermal
from . import glass as glass_mod
from . import ideal as ideal_mod
from .coating import Coating, coating_from_table
from .placement import KEYS as PLACEMENT_KEYS
from .placement import Placement
from .placement import from_row as placement_from_row
from .sag import sag

RIM_SLACK = 1e-9  # relative: a ray aimed exactly at an aperture's rim passes (every tracer)
MAX_BLADES = 64  # an iris's blades (more: a circle to a part in 1e3 of its radius)
NORM_RADIUS_MM = (1e-6, 1e6)  # the Qbfs normalisation radius a surface may have (1 nm to 1 km)
# What a lens file may hold (anything else is a mistake worth naming, e.g. a surface type we do not model)
KEYS = {
    "lens": ("name", "description", "wavelengths_nm", "field_deg", "catalogues", "materials", "temperature_c",
             "pressure_kpa", "surface", "object", "image"),
    "surface": ("label", "radius", "thickness", "diameter", "material", "stop", *shapes.KEYS[1:], "coating", "blades",
                "blade_rotation", "mount", "blade_curvature", "kind", *PLACEMENT_KEYS),
    "object": ("distance", "material"),
    "image": ("diameter", *PLACEMENT_KEYS),
}


def check_keys(table: dict, kind: str, where: str) -> None:
    """SolasError naming each key of `table` that a `kind` table ("lens", "surface", ...) may not hold."""
    unknown = sorted(set(table) - set(KEYS[kind]))
    if unknown:
        raise SolasError(f"{where}: unknown {'key' if len(unknown) == 1 else 'keys'} {', '.join(unknown)} "
                         f"in the {kind} table; allowed: {', '.join(KEYS[kind])}")


def finite_number(table: dict, key: str, where: str, unit: str, default: float | None = None) -> float:
    """table[key] as a finite float; SolasError naming the entry when missing or not a number."""
    if key not in table:
        if default is None:
            raise SolasError(f"{where}: missing '{key}'")
        return default
    value = table[key]
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        raise SolasError(f"{where}: {key} = {value!r} must be a finite number ({unit})")
    return float(value)


def subtable(spec: dict, key: str, where: str) -> dict:
    """spec[key] as a table ({} when absent)."""
    value = spec.get(key, {})
    if not isinstance(value, dict):
        raise SolasError(f"{where}: {key} = {value!r} must be a table ([{key}])")
    return value


def lens_catalogues(spec: dict, where: str) -> tuple[str, ...]:
    """The lens file's `catalogues`: vendors, most preferred first, whose entry a glass name that several
    vendors use means (as a Zemax file's GCAT line)."""
    value = spec.get("catalogues", [])
    vendors = glass_mod.vendors()
    if not isinstance(value, list) or not all(isinstance(v, str) and v.upper() in vendors for v in value):
        raise SolasError(f"{where}: catalogues = {value!r} must be a list of vendors, most preferred first; "
                         f"allowed: {', '.join(vendors)}")
    return tuple(v.upper() for v in value)


def lens_materials(spec: dict, where: str) -> dict[str, glass_mod.Glass]:
    """The lens file's own materials ([materials.NAME] tables, e.g. a CODE V file's private catalogue), by name."""
    return {str(name): glass_mod.own_material(str(name), entry, where)
            for name, entry in subtable(spec, "materials", where).items()}


@dataclass(frozen=True)
class Surface:
    """One sequential surface; `material` fills the space after it, `thickness` reaches the next."""

    label: str
    radius: float  # mm; 0 = flat
    thickness: float  # mm to the next surface (or to the image plane for the last one)
    diameter: float  # clear diameter, mm
    material: str
    glass: glass_mod.Glass
    stop: bool = False
    conic: float = 0.0  # k: 0 sphere, −1 paraboloid, < −1 hyperboloid
    aspheric: tuple[float, ...] = ()  # A4, A6, … (mm^(1−2i)) of the even asphere
    qbfs: tuple[float, ...] = ()  # a0, a1, … (mm) of Forbes' Qbfs departure
    norm_radius: float = 1.0  # ρ (mm): the Qbfs terms' u = r/ρ
    focal_length: float | None = None  # mm: an ideal thin lens (n'·t' = n·t − h/f, `ideal`); None: a real surface
    coating: Coating | None = None  # its thin films (`coating`); None: the bare interface
    blades: int = 0  # the stop's iris: N ≥ 3 straight blades, a regular N-gon with its corners on the clear circle; 0: round
    blade_rotation: float = 0.0  # degrees from +x to the polygon's first corner, counter-clockwise seen from the object
    mount: str | float | None = None  # what holds the air gap after it (`thermal.MOUNTS` or a CTE, 1/K); None: not said
    blade_curvature: float = 0.0  # the iris's sides: 0 straight, κ in (0, 1] arcs of radius (clear radius)/κ
    form: shapes.Shape | None = None  # its shape where not rotationally symmetric (`shapes.NAMED`; radius etc. then 0)
    placement: Placement | None = None  # a coordinate break before it (decentres, tilts); None: on the axis

    def iris_margin(self, x, y, hypot, atan2, cos, floor, constant=float):
        """The signed distance (mm) of points (x, y) inside the stop's aperture: to its rim for a round stop,
        to the nearest blade's edge line for an iris of `blades` (negative outside). Any array type, given
        its functions; `constant` makes the aperture's numbers values of that type (the Dr.Jit tracer: opaque
        kernel inputs)."""
        radius = self.semi_diameter
        if not self.blades:
            return constant(radius) - hypot(x, y)
        sector = 2.0 * math.pi / self.blades
        angle = atan2(y, x) - math.radians(self.blade_rotation)
        within = angle - sector * floor(angle / sector)  # from the sector's first corner, in [0, sector)
        along = hypot(x, y) * cos(within - 0.5 * sector)  # the point's distance along its sector's bisector
        if not self.blade_curvature:
            return constant(radius * math.cos(0.5 * sector)) - along
        # the arc through the sector's two corners, of radius R = r/κ, its centre on the bisector at d (< apex A),
        # as R − |p − centre| = ((A − along)(R + along − d) − across²) / (R + |p − centre|): no cancellation as
        # κ → 0 (R → ∞), where it tends to the straight side's margin
        arc, apex, centre = (constant(v) for v in self.iris_arc())
        across = hypot(x, y) * cos(within - 0.5 * sector - 0.5 * math.pi)
        return ((apex - along) * (arc + along - centre) - across * across) / (arc + hypot(along - centre, across))

    def iris_arc(self) -> tuple[float, float, float]:
        """A curved-blade iris's arc: its radius R = r/κ, the distance from the axis of its apex A (on a sector's
        bisector) and of its centre A − R (r the clear radius, κ `blade_curvature`, corners at half-angle π/N)."""
        r, half = self.semi_diameter, math.pi / self.blades
        arc = r / self.blade_curvature
        chord = r * math.sin(half)  # half the chord between the corners
        apex = r * math.cos(half) + chord * chord / (arc + math.sqrt(arc * arc - chord * chord))
        return arc, apex, apex - arc

    def iris_area(self) -> float:
        """The aperture's area (mm²): the circle, the N-gon (N/2) r² sin(2π/N), or the N-gon and N circular
        segments (R²/2)(2α − sin 2α), sin α = κ sin(π/N), for curved blades."""
        r = self.semi_diameter
        if not self.blades:
            return math.pi * r * r
        polygon = 0.5 * self.blades * r * r * math.sin(2.0 * math.pi / self.blades)
        if not self.blade_curvature:
            return polygon
        arc = r / self.blade_curvature
        alpha = math.asin(self.blade_curvature * math.sin(math.pi / self.blades))
        return polygon + self.blades * 0.5 * arc * arc * (2.0 * alpha - math.sin(2.0 * alpha))

    def prescription(self) -> list:
        """What of this surface changes the optics, for the lens's hash (a kind's terms only where present, so
        a lens file that gains a kind keeps the hashes of the lenses without it)."""
        return ([self.radius, self.thickness, self.diameter, self.glass.name, self.glass.coefficients, self.stop]
                + ([] if self.is_sphere else [self.conic, list(self.aspheric)])
                + ([list(self.qbfs), self.norm_radius] if any(self.qbfs) else [])
                + ([{"focal_length": self.focal_length}] if self.ideal else [])
                + ([{"coating": self.coating.table()}] if self.coating else [])
                + ([{"blades": self.blades, "blade_rotation": self.blade_rotation}] if self.blades else [])
                + ([{"blade_curvature": self.blade_curvature}] if self.blade_curvature else [])
                + ([{"kind": self.form.kind, **self.form.table()}] if self.form else [])
                + ([self.placement.table()] if self.placement else []))

    @cached_property
    def geometry(self) -> shapes.Shape:
        """Its shape as a geometry object (`shapes.KINDS`): `form`, or the rotationally symmetric one of
        its radius, conic, aspheric, qbfs and focal_length."""
        return self.form if self.form is not None else shapes.rotational(self)

    @property
    def kind(self) -> str:
        """Its shape's kind, a name of `shapes.KINDS`."""
        return self.geometry.kind

    @property
    def ideal(self) -> bool:
        """Whether this is an ideal thin lens (`focal_length`), which bends rays without a glass change."""
        return self.focal_length is not None

    @property
    def is_sphere(self) -> bool:
        """A sphere or plane (no conic, no polynomial terms, rotationally symmetric)."""
        return self.conic == 0.0 and not any(self.aspheric) and not any(self.qbfs) and self.form is None

    @property
    def shape(self) -> dict:
        """The keyword arguments of `sag` and `sag_slope` that describe this surface."""
        return {"curvature": self.curvature, "conic": self.conic, "aspheric": self.aspheric, "qbfs": self.qbfs,
                "norm_radius": self.norm_radius}

    def shape_in(self, constant: Callable) -> dict:
        """`shape` with its numbers but the Qbfs terms (which `sag` tests) made values of an array type by
        `constant`: the Dr.Jit tracer's opaque kernel inputs, so a drawn radius or irregularity reuses its
        compiled kernels."""
        return {**self.shape, **{key: constant(getattr(self, key)) for key in ("curvature", "conic", "norm_radius")},
                "aspheric": tuple(constant(a) for a in self.aspheric)}

    @property
    def paraxial_curvature(self) -> float:
        """1/mm: the vertex curvature, c + 2 Σ a_m Q_m^bfs(0)/ρ² where Qbfs terms bend the vertex too; for a
        surface without rotational symmetry, its y-z section's (paraxial data in the y-z plane, as Zemax's)."""
        if self.form is not None:
            return self.form.section_curvatures[1]
        bend = forbes.qbfs_sum(0.0, self.qbfs)[0] if any(self.qbfs) else 0.0
        return self.curvature + 2.0 * bend / self.norm_radius ** 2

    @property
    def curvature(self) -> float:
        """1/R in 1/mm (0 for a flat surface)."""
        return 0.0 if self.radius == 0.0 else 1.0 / self.radius

    @property
    def semi_diameter(self) -> float:
        return 0.5 * self.diameter

    def sag(self, r: np.ndarray | float) -> np.ndarray | float:
        """Surface z relative to its vertex at radial distance r (mm); for a surface without rotational
        symmetry, along its y-z section."""
        r = np.asarray(r, dtype=np.float64)
        if self.form is not None:
            return self.form.sag(0.0 * r, r)
        return sag(r * r, **self.shape)


def surface_from_row(row: dict, i: int, where: str, catalogues: tuple[str, ...], own: dict) -> Surface:
    """Surface `i` (1-based) of a lens file's [[surface]] table, checked."""
    label = str(row.get("label", f"surface {i}"))
    ident = f"{where}: surface {i} ({label})"
    check_keys(row, "surface", ident)
    form, placement = shape_form(row, ident), placement_from_row(row, ident, finite_number)
    if form is not None:  # the kind's entries are its own: the rest of the row as a flat surface's
        row = {k: v for k, v in row.items() if k not in ("kind", *shapes.KINDS[form.kind].extra["keys"])}
        row["radius"] = 0.0
    stop = row.get("stop", False)
    if not isinstance(stop, bool):
        raise SolasError(f"{ident}: stop = {stop!r} must be true or false (a TOML boolean, unquoted)")
    radius, thickness, diameter = (finite_number(row, key, ident, "mm") for key in ("radius", "thickness", "diameter"))
    conic = finite_number(row, "conic", ident, "conic constant k, dimensionless", 0.0)
    aspheric = polynomial_terms(row, "aspheric", ident, "[A4, A6, ...] (mm^(1-2i))")
    qbfs = polynomial_terms(row, "qbfs", ident, "[a0, a1, ...] of Forbes' Qbfs polynomials (mm)")
    norm_radius = finite_number(row, "norm_radius", ident, "mm, the Qbfs normalisation radius", 0.0 if qbfs else 1.0)
    if not NORM_RADIUS_MM[0] <= norm_radius <= NORM_RADIUS_MM[1]:  # 0: a division by zero, 1e300: an overflow
        raise SolasError(f"{ident}: {'qbfs needs ' if qbfs else ''}norm_radius, the radius where the Qbfs terms' "
                         f"u = 1, from {NORM_RADIUS_MM[0]:g} to {NORM_RADIUS_MM[1]:g} mm; got {row.get('norm_radius')!r}")
    focal_length = (ideal_mod.check(row["focal_length"], ident, radius == conic == 0 and not any(aspheric + qbfs))
                    if "focal_length" in row else None)
    material = row.get("material", "AIR")
    try:
        g = glass_mod.resolve(material, prefer=catalogues, own=own)
    except SolasError as exc:
        raise SolasError(f"{ident}: {exc}") from None
    coating = coating_from_table(row["coating"], ident) if "coating" in row else None
    blades, rotation, curvature = _iris(row, ident, stop)
    mount = row.get("mount")
    if mount is not None:
        try:
            thermal.mount_cte(mount)
        except SolasError as exc:
            raise SolasError(f"{ident}: {exc}") from None
    return Surface(label, radius, thickness, diameter, str(material), g, stop, conic, aspheric, qbfs, norm_radius,
                   focal_length, coating, blades, rotation, mount, curvature, form, placement)


def _iris(row: dict, ident: str, stop: bool) -> tuple[int, float, float]:
    """A row's iris: blades, blade_rotation (degrees) and blade_curvature; SolasError naming a bad one."""
    blades, rotation = row.get("blades", 0), finite_number(row, "blade_rotation", ident, "degrees", 0.0)
    if not isinstance(blades, int) or isinstance(blades, bool) or not (blades == 0 or 3 <= blades <= MAX_BLADES) \
            or ((blades or "blade_rotation" in row) and not stop):
        raise SolasError(f"{ident}: blades = {blades!r} must be 0 (a round stop) or an integer from 3 to {MAX_BLADES}, "
                         "with blade_rotation (degrees), on the stop surface only")
    curvature = finite_number(row, "blade_curvature", ident, "the blades' curvature", 0.0)
    if not 0.0 <= curvature <= 1.0 or ("blade_curvature" in row and not blades):
        raise SolasError(f"{ident}: blade_curvature = {row['blade_curvature']!r} must be from 0 (straight blades) to 1 "
                         "(arcs of the clear circle), with blades")
    return blades, rotation, curvature


def shape_form(row: dict, ident: str) -> shapes.Shape | None:
    """The shape a row names by `kind` (`shapes.NAMED`), of its kind's entries, checked; None without `kind`."""
    if "kind" not in row:
        symmetric = {key for _, entry in shapes.KINDS.items() if entry.extra["symmetric"] for key in entry.extra["keys"]}
        named = [key for key in shapes.KEYS if key in row and key not in symmetric]  # else dropped unread
        if named:
            kinds = [kind for kind in shapes.NAMED if named[0] in shapes.KINDS[kind].extra["keys"]]
            raise SolasError(f"{ident}: {', '.join(named)} without kind: a surface with {named[0]} needs kind = "
                             f"{' or '.join(repr(k) for k in kinds)} (a rotationally symmetric surface takes none)")
        return None
    kind = row["kind"]
    if kind not in shapes.NAMED:
        raise SolasError(f"{ident}: kind = {kind!r} must be one of {', '.join(shapes.NAMED)} (a rotationally "
                         "symmetric surface takes no kind: radius, conic, aspheric, qbfs or focal_length say it)")
    entry = shapes.KINDS[kind]
    stray = [key for key in shapes.KEYS if key in row and key not in entry.extra["keys"]]
    if stray:
        raise SolasError(f"{ident}: a {kind} takes {', '.join(entry.extra['keys'])}; not {', '.join(stray)}")
    values = {key: polynomial_terms(row, key, ident, "(mm^(1-2i))") if key in entry.extra["lists"]
              else finite_number(row, key, ident, "mm" if key.startswith("radius") else "dimensionless",
                                 None if key == "radius" else 0.0)
              for key in entry.extra["keys"]}
    return entry.function(**values)


def polynomial_terms(row: dict, key: str, ident: str, meaning: str) -> tuple[float, ...]:
    """row[key], a list of at most 12 finite numbers, as a tuple (() when absent)."""
    terms = row.get(key, [])
    if (not isinstance(terms, list) or len(terms) > 12
            or not all(isinstance(a, (int, float)) and not isinstance(a, bool) and math.isfinite(a) for a in terms)):
        raise SolasError(f"{ident}: {key} = {terms!r} must be a list of at most 12 finite numbers {meaning}")
    return tuple(float(a) for a in terms)
