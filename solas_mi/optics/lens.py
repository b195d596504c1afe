"""A lens prescription: surfaces, glass, object and image plane, loaded from a lens file (our TOML, or
another program's: `formats.READERS`).

Lengths in mm, wavelengths in nm, field angles in degrees. +z is the optical axis toward the image;
surface 1's vertex is at z = 0. A surface is a sphere, or an even asphere: sag
z(r) = c r² / (1 + √(1 − (1 + k) c² r²)) + Σ_i A_2i r^2i (i ≥ 2) with c = 1/radius, k = `conic` and
`aspheric` = [A4, A6, …] (mm^(1−2i)), plus Forbes' Qbfs departure φ u²(1 − u²) Σ a_m Q_m^bfs(u²) with
`qbfs` = [a0, a1, …] (mm) and u = r / `norm_radius` (`forbes`). A flat surface with `focal_length` (mm)
is an ideal thin lens (`ideal`).
"""
from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SolasError
from ..imageio import write_text
from . import forbes, ideal as ideal_mod, overlap
from . import glass as glass_mod
from .sag import sag
from .formats import (MAX_SURFACES, MAX_WAVELENGTHS, READERS, WRITERS, check_count, check_printable, lens_path,
                      shipped_lenses, writable)  # noqa: F401 (shipped_lenses: re-exported)
from .fields import FieldType, field_type_for

NORM_RADIUS_MM = (1e-6, 1e6)  # the Qbfs normalisation radius a surface may have (1 nm to 1 km)
# The longest length a lens file may give (mm): an object beyond it is at infinity to every digit (its image
# lies f²/d ≈ 1e-11 mm from the focus of an f = 100 mm lens); a film 1e30 mm away rendered NaN, one at 1e300
# overflowed lens info's projection fits.
MAX_LENGTH_MM = 1e15
_VIRTUAL = ": the image plane lies before the last surface, a virtual image (a diverging lens's focus) that no film records"
# What a lens file may hold (anything else is a mistake worth naming, e.g. a surface type we do not model)
KEYS = {
    "lens": ("name", "description", "wavelengths_nm", "field_deg", "catalogues", "materials", "surface", "object",
             "image"),
    "surface": ("label", "radius", "thickness", "diameter", "material", "stop", "conic", "aspheric", "qbfs",
                "norm_radius", "focal_length"),
    "object": ("distance", "material"),
    "image": ("diameter",),
}


def check_lens(lens) -> None:
    """SolasError unless `lens` is a Lens (analyses take `Lens.load(name or path)`)."""
    if not isinstance(lens, Lens):
        raise SolasError(f"lens {lens!r} must be a Lens: Lens.load(a shipped name or a lens file)")


def _check_size(surfaces, wavelengths, where: str) -> None:
    """SolasError unless there are at most `formats.MAX_SURFACES` surfaces and `MAX_WAVELENGTHS` wavelengths."""
    check_count(len(surfaces), "surfaces", MAX_SURFACES, where)
    check_count(len(wavelengths), "wavelengths", MAX_WAVELENGTHS, where)


def _check_keys(table: dict, kind: str, where: str) -> None:
    unknown = sorted(set(table) - set(KEYS[kind]))
    if unknown:
        raise SolasError(f"{where}: unknown {'key' if len(unknown) == 1 else 'keys'} {', '.join(unknown)} "
                         f"in the {kind} table; allowed: {', '.join(KEYS[kind])}")


def _number(table: dict, key: str, where: str, unit: str, default: float | None = None) -> float:
    """table[key] as a finite float; SolasError naming the entry when missing or not a number."""
    if key not in table:
        if default is None:
            raise SolasError(f"{where}: missing '{key}'")
        return default
    value = table[key]
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        raise SolasError(f"{where}: {key} = {value!r} must be a finite number ({unit})")
    return float(value)


def _catalogues(spec: dict, where: str) -> tuple[str, ...]:
    """The lens file's `catalogues`: vendors, most preferred first, whose entry a glass name that several
    vendors use means (as a Zemax file's GCAT line)."""
    value = spec.get("catalogues", [])
    vendors = glass_mod.vendors()
    if not isinstance(value, list) or not all(isinstance(v, str) and v.upper() in vendors for v in value):
        raise SolasError(f"{where}: catalogues = {value!r} must be a list of vendors, most preferred first; "
                         f"allowed: {', '.join(vendors)}")
    return tuple(v.upper() for v in value)


def _own_materials(spec: dict, where: str) -> dict[str, glass_mod.Glass]:
    """The lens file's own materials ([materials.NAME] tables, e.g. a CODE V file's private catalogue), by name."""
    return {str(name): glass_mod.own_material(str(name), entry, where)
            for name, entry in _table(spec, "materials", where).items()}


def _table(spec: dict, key: str, where: str) -> dict:
    """spec[key] as a table ({} when absent)."""
    value = spec.get(key, {})
    if not isinstance(value, dict):
        raise SolasError(f"{where}: {key} = {value!r} must be a table ([{key}])")
    return value


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

    @property
    def ideal(self) -> bool:
        """Whether this is an ideal thin lens (`focal_length`), which bends rays without a glass change."""
        return self.focal_length is not None

    @property
    def is_sphere(self) -> bool:
        """A sphere or plane (no conic, no polynomial terms)."""
        return self.conic == 0.0 and not any(self.aspheric) and not any(self.qbfs)

    @property
    def shape(self) -> dict:
        """The keyword arguments of `sag` and `sag_slope` that describe this surface."""
        return {"curvature": self.curvature, "conic": self.conic, "aspheric": self.aspheric, "qbfs": self.qbfs,
                "norm_radius": self.norm_radius}

    @property
    def paraxial_curvature(self) -> float:
        """1/mm: the vertex curvature, c + 2 Σ a_m Q_m^bfs(0)/ρ² where Qbfs terms bend the vertex too."""
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
        """Surface z relative to its vertex at radial distance r (mm)."""
        r = np.asarray(r, dtype=np.float64)
        return sag(r * r, **self.shape)


def _surface(row: dict, i: int, where: str, catalogues: tuple[str, ...], own: dict) -> "Surface":
    """Surface `i` (1-based) of a lens file's [[surface]] table, checked."""
    label = str(row.get("label", f"surface {i}"))
    ident = f"{where}: surface {i} ({label})"
    _check_keys(row, "surface", ident)
    stop = row.get("stop", False)
    if not isinstance(stop, bool):
        raise SolasError(f"{ident}: stop = {stop!r} must be true or false (a TOML boolean, unquoted)")
    radius, thickness, diameter = (_number(row, key, ident, "mm") for key in ("radius", "thickness", "diameter"))
    conic = _number(row, "conic", ident, "conic constant k, dimensionless", 0.0)
    aspheric = _terms(row, "aspheric", ident, "[A4, A6, ...] (mm^(1-2i))")
    qbfs = _terms(row, "qbfs", ident, "[a0, a1, ...] of Forbes' Qbfs polynomials (mm)")
    norm_radius = _number(row, "norm_radius", ident, "mm, the Qbfs normalisation radius", 0.0 if qbfs else 1.0)
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
    return Surface(label, radius, thickness, diameter, str(material), g, stop, conic, aspheric, qbfs, norm_radius,
                   focal_length)


def _terms(row: dict, key: str, ident: str, meaning: str) -> tuple[float, ...]:
    """row[key], a list of at most 12 finite numbers, as a tuple (() when absent)."""
    terms = row.get(key, [])
    if (not isinstance(terms, list) or len(terms) > 12
            or not all(isinstance(a, (int, float)) and not isinstance(a, bool) and math.isfinite(a) for a in terms)):
        raise SolasError(f"{ident}: {key} = {terms!r} must be a list of at most 12 finite numbers {meaning}")
    return tuple(float(a) for a in terms)


@dataclass(frozen=True)
class Lens:
    """A sequential lens: data only. Load with `Lens.load("solas-doublet")` or a path to a lens file;
    analyses take it as an argument (`solas_mi.paraxial(lens)`, `solas_mi.psf.psf(lens, ...)`)."""

    name: str
    surfaces: tuple[Surface, ...]
    object_distance: float = math.inf  # mm from the object to surface 1
    object_glass: glass_mod.Glass = glass_mod.AIR
    image_diameter: float = 0.0
    wavelengths_nm: tuple[float, ...] = (486.0, 531.0, 656.0)
    field_deg: float = 0.0
    description: str = ""
    source: str = ""
    catalogues: tuple[str, ...] = ()  # vendors whose entry a glass name shared by several vendors means, first first
    materials: tuple[glass_mod.Glass, ...] = ()  # the lens file's own materials, which its surfaces name

    def __post_init__(self) -> None:
        """However it is built (a file, `from_dict`, this constructor, `dataclasses.replace`), a lens holds
        at most `formats.MAX_SURFACES` surfaces and `MAX_WAVELENGTHS` wavelengths (why: `formats`), and
        its texts are printable (`formats.check_printable`)."""
        _check_size(self.surfaces, self.wavelengths_nm, self.source or self.name)
        for what, text in (("name", self.name), ("description", self.description),
                           *(("surface label", s.label) for s in self.surfaces)):
            check_printable(text, what, self.source or "lens")

    # ------------------------------------------------------------------ loading
    @classmethod
    def load(cls, name_or_path: str | Path) -> "Lens":
        """A lens by shipped name (e.g. "solas-doublet") or by path to a lens file (`formats.readable()`):
        a name holding a path separator or an extension is a path."""
        path = lens_path(name_or_path)
        reader = READERS[path.suffix.lower()]
        lens = cls.from_dict(reader.function(path), source=str(path))
        if "check" in reader.extra:  # what a lens read from this format must hold beyond any lens's checks
            reader.extra["check"](lens)
        return lens

    def save(self, path: str | Path) -> Path:
        """Write the lens to `path` (written whole or not at all) in the format its extension names:
        one of `formats.writable()`."""
        path = Path(path)
        if path.suffix.lower() not in WRITERS:
            raise SolasError(f"lens file {str(path)!r}: unknown extension {path.suffix!r}; "
                             f"allowed: {writable()}")
        write_text(path, WRITERS[path.suffix.lower()].function(self))
        return path

    @classmethod
    def from_dict(cls, spec: dict[str, Any], source: str = "") -> "Lens":
        """Build and validate a lens from the lens-file dictionary."""
        where = source or "lens"
        _check_keys(spec, "lens", where)
        rows = spec.get("surface")
        if not isinstance(rows, list) or not rows:
            raise SolasError(f"{where}: no [[surface]] entries (each surface is a table of radius, thickness, ...)")
        if not all(isinstance(r, dict) for r in rows):
            raise SolasError(f"{where}: surface = {rows!r}: each surface must be a table ([[surface]] with radius, "
                             "thickness, ...)")
        wavelengths = spec.get("wavelengths_nm", [486.0, 531.0, 656.0])
        if not isinstance(wavelengths, list) or not wavelengths:
            raise SolasError(f"{where}: wavelengths_nm = {wavelengths!r} must be a non-empty list of numbers (nm)")
        _check_size(rows, wavelengths, where)  # before any work on them
        catalogues, own = _catalogues(spec, where), _own_materials(spec, where)
        surfaces = [_surface(row, i, where, catalogues, own) for i, row in enumerate(rows, start=1)]
        obj, image = _table(spec, "object", where), _table(spec, "image", where)
        _check_keys(obj, "object", f"{where}: object")
        _check_keys(image, "image", f"{where}: image")
        distance = obj.get("distance", "infinity")
        if isinstance(distance, str) and distance.strip().lower() in ("inf", "infinity"):
            distance = math.inf
        elif (not isinstance(distance, (int, float)) or isinstance(distance, bool) or not math.isfinite(distance)
              or distance == 0):
            raise SolasError(f"{where}: object distance {distance!r} must be a non-zero number (mm; negative: a "
                             "virtual object behind surface 1, light converging toward it) or \"infinity\"")
        try:
            object_glass = glass_mod.resolve(obj.get("material", "AIR"), prefer=catalogues, own=own)
        except SolasError as exc:
            raise SolasError(f"{where}: object: {exc}") from None
        lens = cls(
            name=str(spec.get("name", Path(source).stem if source else "lens")),
            surfaces=tuple(surfaces),
            object_distance=float(distance),
            object_glass=object_glass,
            image_diameter=_number(image, "diameter", f"{where}: image", "mm", 0.0),
            wavelengths_nm=tuple(_number({"wavelengths_nm": w}, "wavelengths_nm", where, "nm") for w in wavelengths),
            field_deg=_number(spec, "field_deg", where, "degrees", 0.0),
            description=str(spec.get("description", "")),
            source=source,
            catalogues=catalogues,
            materials=tuple(own.values()),
        )
        lens._validate(where)
        return lens

    def _validate(self, where: str) -> None:
        if not 0 <= self.field_deg < 180:
            raise SolasError(f"{where}: field_deg = {self.field_deg:g} must be a half field angle in [0, 180) degrees")
        for w in self.wavelengths_nm:
            if not w > 0:
                raise SolasError(f"{where}: wavelengths_nm holds {w:g}; wavelengths must be positive (nm)")
        if not 0 <= self.image_diameter <= MAX_LENGTH_MM:
            raise SolasError(f"{where}: image diameter {self.image_diameter:g} mm must be positive, at most "
                             f"{MAX_LENGTH_MM:g} mm (or left out)")
        stops = [i for i, s in enumerate(self.surfaces) if s.stop]
        if not stops:
            raise SolasError(f"{where}: no surface is marked as the aperture stop (set stop = true on one)")
        if len(stops) > 1:
            raise SolasError(f"{where}: surfaces {', '.join(str(i + 1) for i in stops)} are all marked stop; exactly one may be")
        if not abs(self.object_distance) <= MAX_LENGTH_MM and math.isfinite(self.object_distance):
            raise SolasError(f"{where}: object distance {self.object_distance:g} mm must lie within ±{MAX_LENGTH_MM:g} "
                             "mm, or be \"infinity\" (a farther object is at infinity to every digit)")
        for i, s in enumerate(self.surfaces, start=1):
            ident = f"{where}: surface {i} ({s.label})"
            if not 0 < s.diameter <= MAX_LENGTH_MM:
                raise SolasError(f"{ident}: diameter {s.diameter:g} mm must be positive and at most {MAX_LENGTH_MM:g} mm")
            if not abs(s.thickness) <= MAX_LENGTH_MM:
                raise SolasError(f"{ident}: thickness {s.thickness:g} mm must lie within ±{MAX_LENGTH_MM:g} mm, the "
                                 "longest length a lens file may give")
            if s.radius != 0 and s.conic == 0 and s.semi_diameter >= abs(s.radius):
                raise SolasError(f"{ident}: clear semi-diameter {s.semi_diameter:g} mm is not smaller than |radius| "
                                 f"{abs(s.radius):g} mm; the sphere cannot hold that aperture")
            if s.conic != 0 and (1.0 + s.conic) * (s.curvature * s.semi_diameter) ** 2 >= 1.0:
                raise SolasError(f"{ident}: conic {s.conic:g} with radius {s.radius:g} mm closes before the clear "
                                 f"semi-diameter {s.semi_diameter:g} mm; the conic cannot hold that aperture")
        self.field_type.check_lens(self, where)
        last = self.surfaces[-1]
        if last.thickness < 0:
            raise SolasError(f"{where}: surface {len(self.surfaces)} ({last.label}): distance to the image "
                             f"{last.thickness:g} mm must be positive" + _VIRTUAL + "; 0 mm puts it on the last surface")
        overlap.notes(self, where)

    @property
    def overlaps(self) -> tuple[str, ...]:
        """What overlaps along the axis, one sentence each (`overlap`): faces that cross inside their clear
        apertures, an image plane on the last surface; empty for a lens that can be built as solid geometry."""
        return tuple(overlap.notes(self, self.source or "lens"))

    # ------------------------------------------------------------------ geometry
    @property
    def stop_index(self) -> int:
        return next(i for i, s in enumerate(self.surfaces) if s.stop)

    @property
    def vertex_z(self) -> np.ndarray:
        """z of each surface vertex (mm), surface 1 at 0."""
        return np.concatenate([[0.0], np.cumsum([s.thickness for s in self.surfaces[:-1]])])

    @property
    def image_z(self) -> float:
        """z of the image plane (mm)."""
        return float(self.vertex_z[-1] + self.surfaces[-1].thickness)

    @property
    def field_type(self) -> FieldType:
        """What a field (x, y) in degrees means for this lens (`fields`): angle fields (tangents), or
        polar fields for a lens whose `field_deg` reaches `fields.POLAR_FIELD_DEG`."""
        return field_type_for(self.field_deg)

    @property
    def dispersive(self) -> bool:
        """Whether any medium's index depends on wavelength: a lens read without dispersion data (a
        pbrt table of n_d alone) focuses every colour alike, which `lens info` and PSF metadata state."""
        return any(g.dispersive for g in (self.object_glass, *(s.glass for s in self.surfaces)))

    @property
    def at_infinity(self) -> bool:
        return math.isinf(self.object_distance)

    @property
    def virtual_object(self) -> bool:
        """Whether the object lies behind surface 1 (a negative `object_distance`; `virtual_object`)."""
        return self.object_distance < 0

    def indices(self, wavelength_nm: float) -> np.ndarray:
        """Refractive index of the object space and after each surface at `wavelength_nm`."""
        return np.array([self.object_glass.index(wavelength_nm)] + [s.glass.index(wavelength_nm) for s in self.surfaces])

    @property
    def hash(self) -> str:
        """Short SHA-256 of the optical prescription (what changes the optics, not labels)."""
        content = {
            "object": [self.object_distance if math.isfinite(self.object_distance) else "inf", self.object_glass.name],
            "surfaces": [[s.radius, s.thickness, s.diameter, s.glass.name, s.glass.coefficients, s.stop]
                         + ([] if s.is_sphere else [s.conic, list(s.aspheric)])
                         + ([list(s.qbfs), s.norm_radius] if any(s.qbfs) else [])
                         + ([{"focal_length": s.focal_length}] if s.ideal else []) for s in self.surfaces],
        }
        return hashlib.sha256(json.dumps(content, sort_keys=True).encode()).hexdigest()[:16]

    def check_wavelength(self, wavelength_nm: float) -> float:
        """`wavelength_nm` as float after checking every glass accepts it."""
        if (not isinstance(wavelength_nm, (int, float, np.integer, np.floating)) or isinstance(wavelength_nm, bool)
                or not math.isfinite(wavelength_nm) or wavelength_nm <= 0):
            raise SolasError(f"wavelength {wavelength_nm!r} nm must be a positive number")
        self.indices(float(wavelength_nm))
        return float(wavelength_nm)

    @property
    def primary_wavelength(self) -> float:
        """The middle design wavelength (nm)."""
        return sorted(self.wavelengths_nm)[len(self.wavelengths_nm) // 2]
