"""A lens prescription: surfaces (`surface.Surface`: a sphere, an even asphere with Forbes' Qbfs terms,
or an ideal thin lens), glass, object and image plane, loaded from a lens file (our TOML, or another
program's: `formats.READERS`).

Lengths in mm, wavelengths in nm, field angles in degrees. +z is the optical axis toward the image;
surface 1's vertex is at z = 0.
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
from . import glass as glass_mod
from . import lens_checks, overlap, placement, thermal
from .fields import FieldType, field_type_for
from .formats import READERS, WRITERS, check_printable, lens_path, writable
from .formats import shipped_lenses as shipped_lenses  # re-exported
from .sag import sag as sag  # re-exported
from .surface import NORM_RADIUS_MM as NORM_RADIUS_MM  # re-exported
from .surface import Surface, check_keys, finite_number, lens_catalogues, lens_materials, subtable, surface_from_row


def check_lens(lens) -> None:
    """SolasError unless `lens` is a Lens (analyses take `Lens.load(name or path)`)."""
    if not isinstance(lens, Lens):
        raise SolasError(f"lens {lens!r} must be a Lens: Lens.load(a shipped name or a lens file)")


@dataclass(frozen=True)
class Lens:
    """A sequential lens: data only, frozen; analyses take it as their first argument.

    Load one with `Lens.load` (a shipped name or a lens file); `from_dict` builds one from a lens file's
    table, and `dataclasses.replace` a changed copy. Lengths in mm, wavelengths in nm.

    Parameters
    ----------
    name : str
        The lens's name.
    surfaces : tuple of Surface
        The sequential surfaces, object side first (`solas_mi.optics.surface.Surface`).
    object_distance : float, default inf
        From the object to surface 1 (mm); negative: a virtual object behind surface 1.
    object_glass : Glass, default air
        The medium in front of surface 1.
    image_diameter : float, default 0
        The image circle's diameter (mm); 0: not given.
    wavelengths_nm : tuple of float, default (486, 531, 656)
        The design wavelengths (nm).
    field_deg : float, default 0
        The half field angle (degrees).
    description : str, default ""
        What the lens is, in words.
    source : str, default ""
        The file it was read from ("": built in memory).
    catalogues : tuple of str, default ()
        Glass vendors, most preferred first, whose entry a glass name that several vendors use means.
    materials : tuple of Glass, default ()
        The lens file's own materials, which its surfaces name.
    temperature_c : float, default 20
        The temperature (°C) of the lens and the air around it; its media's indices hold there (`at`).
    pressure_kpa : float, default 101.325
        The air's pressure (kPa); indices are relative to that air.
    image_placement : Placement, optional
        A coordinate break before the image plane: the sensor decentred or tilted (`placement`).

    Raises
    ------
    SolasError
        For more than `formats.MAX_SURFACES` surfaces or `formats.MAX_WAVELENGTHS` wavelengths.

    Examples
    --------
    >>> from solas_mi import Lens
    >>> lens = Lens.load("solas-doublet")
    >>> lens.name, len(lens.surfaces), lens.wavelengths_nm
    ('solas-doublet', 4, (486.0, 531.0, 656.0))
    """

    name: str
    surfaces: tuple[Surface, ...]
    object_distance: float = math.inf
    object_glass: glass_mod.Glass = glass_mod.AIR
    image_diameter: float = 0.0
    wavelengths_nm: tuple[float, ...] = (486.0, 531.0, 656.0)
    field_deg: float = 0.0
    description: str = ""
    source: str = ""
    catalogues: tuple[str, ...] = ()
    materials: tuple[glass_mod.Glass, ...] = ()
    temperature_c: float = thermal.STANDARD_C
    pressure_kpa: float = thermal.STANDARD_KPA
    image_placement: placement.Placement | None = None

    def __post_init__(self) -> None:
        """However it is built (a file, `from_dict`, this constructor, `dataclasses.replace`), a lens holds
        at most `formats.MAX_SURFACES` surfaces and `MAX_WAVELENGTHS` wavelengths (why: `formats`), and
        its texts are printable (`formats.check_printable`)."""
        lens_checks.check_size(self.surfaces, self.wavelengths_nm, self.source or self.name)
        for what, text in (("name", self.name), ("description", self.description),
                           *(("surface label", s.label) for s in self.surfaces)):
            check_printable(text, what, self.source or "lens")

    # ------------------------------------------------------------------ loading
    @classmethod
    def load(cls, name_or_path: str | Path) -> Lens:
        """A lens by its shipped name or from a lens file.

        Parameters
        ----------
        name_or_path : str or Path
            A shipped lens's name (``solas-mi lens list``), or the path of a lens file of a format
            `formats.READERS` reads; a name holding a path separator or an extension is a path.

        Returns
        -------
        Lens
            The lens, checked.

        Raises
        ------
        SolasError
            For an unknown name, a file that cannot be read, or a lens file's mistake (named with its line or
            surface).

        Examples
        --------
        >>> from solas_mi import Lens
        >>> Lens.load("solas-doublet").stop_index
        3
        >>> Lens.load("scenes/lenses/cooke_triplet.toml").name
        'cooke-triplet'
        """
        path = lens_path(name_or_path)
        reader = READERS[path.suffix.lower()]
        lens = cls.from_dict(reader.function(path), source=str(path))
        if "check" in reader.extra:  # what a lens read from this format must hold beyond any lens's checks
            reader.extra["check"](lens)
        return lens

    def save(self, path: str | Path) -> Path:
        """Write the lens to a lens file, whole or not at all.

        Parameters
        ----------
        path : str or Path
            Where; its extension names the format, one `formats.WRITERS` writes.

        Returns
        -------
        Path
            `path`.

        Raises
        ------
        SolasError
            For an extension no writer takes, or a lens the format cannot hold.

        Examples
        --------
        >>> from solas_mi import Lens
        >>> lens = Lens.load("solas-doublet")
        >>> Lens.load(lens.save("doublet.toml")).hash == lens.hash
        True
        """
        path = Path(path)
        if path.suffix.lower() not in WRITERS:
            raise SolasError(f"lens file {str(path)!r}: unknown extension {path.suffix!r}; "
                             f"allowed: {writable()}")
        writer = WRITERS[path.suffix.lower()]
        for feature, used in lens_checks.features(self):
            if used and feature not in writer.extra.get("holds", ()):
                raise SolasError(f"lens file {str(path)!r}: a {path.suffix} file holds no {feature}; save the lens "
                                 f"as {', '.join(k for k, e in WRITERS.items() if feature in e.extra.get('holds', ()))}")
        write_text(path, writer.function(self))
        return path

    # long: the public API's numpydoc docstring is a third of it
    @classmethod
    def from_dict(cls, spec: dict[str, Any], source: str = "") -> Lens:
        """Build and check a lens from a lens file's table (our TOML's keys, [lens-file format](../lens-files.md)).

        Parameters
        ----------
        spec : dict
            The table: name, wavelengths_nm, field_deg, [[surface]] rows, object, image, ...
        source : str, default ""
            Where it came from, named in messages and kept as `source`.

        Returns
        -------
        Lens
            The lens, checked.

        Raises
        ------
        SolasError
            For an unknown key, a missing or bad value, a glass that resolves to no catalogue entry or to
            several, no stop or several; the message names the surface.
        """
        where = source or "lens"
        check_keys(spec, "lens", where)
        rows = spec.get("surface")
        if not isinstance(rows, list) or not rows:
            raise SolasError(f"{where}: no [[surface]] entries (each surface is a table of radius, thickness, ...)")
        if not all(isinstance(r, dict) for r in rows):
            raise SolasError(f"{where}: surface = {rows!r}: each surface must be a table ([[surface]] with radius, "
                             "thickness, ...)")
        wavelengths = spec.get("wavelengths_nm", [486.0, 531.0, 656.0])
        if not isinstance(wavelengths, list) or not wavelengths:
            raise SolasError(f"{where}: wavelengths_nm = {wavelengths!r} must be a non-empty list of numbers (nm)")
        lens_checks.check_size(rows, wavelengths, where)  # before any work on them
        catalogues, own = lens_catalogues(spec, where), lens_materials(spec, where)
        surfaces = [surface_from_row(row, i, where, catalogues, own) for i, row in enumerate(rows, start=1)]
        obj, image = subtable(spec, "object", where), subtable(spec, "image", where)
        check_keys(obj, "object", f"{where}: object")
        check_keys(image, "image", f"{where}: image")
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
            image_diameter=finite_number(image, "diameter", f"{where}: image", "mm", 0.0),
            image_placement=placement.from_row(image, f"{where}: image", finite_number),
            wavelengths_nm=tuple(finite_number({"wavelengths_nm": w}, "wavelengths_nm", where, "nm") for w in wavelengths),
            field_deg=finite_number(spec, "field_deg", where, "degrees", 0.0),
            description=str(spec.get("description", "")),
            source=source,
            catalogues=catalogues,
            materials=tuple(own.values()),
        )
        lens_checks.validate(lens, where)
        environment = [finite_number(spec, key, where, unit, default) for key, unit, default in (
            ("temperature_c", "°C", thermal.STANDARD_C), ("pressure_kpa", "kPa", thermal.STANDARD_KPA))]
        try:
            return thermal.in_environment(lens, *environment)
        except SolasError as exc:
            raise SolasError(f"{where}: {exc}") from None

    @property
    def overlaps(self) -> tuple[str, ...]:
        """What overlaps along the axis, one sentence each (`overlap`): faces that cross inside their clear
        apertures, an image plane on the last surface; empty for a lens that can be built as solid geometry."""
        return tuple(overlap.notes(self, self.source or "lens"))

    # ------------------------------------------------------------------ geometry
    @property
    def stop_index(self) -> int:
        """The index of the aperture stop among `surfaces` (0-based)."""
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
        """Whether the object is at infinity (fields are angles of collimated light)."""
        return math.isinf(self.object_distance)

    @property
    def virtual_object(self) -> bool:
        """Whether the object lies behind surface 1 (a negative `object_distance`; `virtual_object`)."""
        return self.object_distance < 0

    def indices(self, wavelength_nm: float) -> np.ndarray:
        """The refractive index of each medium at one wavelength.

        Parameters
        ----------
        wavelength_nm : float
            The wavelength (nm).

        Returns
        -------
        numpy.ndarray
            (len(surfaces) + 1,): the object space's index, then the index after each surface.
        """
        return np.array([self.object_glass.index(wavelength_nm)] + [s.glass.index(wavelength_nm) for s in self.surfaces])

    @property
    def hash(self) -> str:
        """Short SHA-256 of the optical prescription (what changes the optics, not labels)."""
        content = {
            "object": [self.object_distance if math.isfinite(self.object_distance) else "inf", self.object_glass.name],
            "surfaces": [s.prescription() for s in self.surfaces],
        }
        if (self.temperature_c, self.pressure_kpa) != (thermal.STANDARD_C, thermal.STANDARD_KPA):
            content["environment"] = [self.temperature_c, self.pressure_kpa]  # the indices change with it
        if self.image_placement:
            content["image_placement"] = self.image_placement.table()
        return hashlib.sha256(json.dumps(content, sort_keys=True).encode()).hexdigest()[:16]

    def at(self, temperature_c: float = thermal.STANDARD_C, pressure_kpa: float = thermal.STANDARD_KPA,
           mount=None) -> Lens:
        """This lens at another temperature and air pressure (`thermal`): glass indices by the Schott
        formula relative to the air there, glass and mount expanded from this lens's temperature.

        Parameters
        ----------
        temperature_c : float, default 20
            The temperature (°C) of the lens, its mount and the air.
        pressure_kpa : float, default 101.325
            The air's pressure (kPa).
        mount : str, float or sequence, optional
            What holds the air gaps: a material of `thermal.MOUNTS` or a CTE (1/K), for every gap, or one
            per surface (the gap after it); default: each surface's `mount` (its lens file's), aluminium
            where it has none.

        Returns
        -------
        Lens
            The lens there; itself at its own temperature and pressure. A glass without thermal data
            keeps its absolute index and size, which a warning names.

        Raises
        ------
        SolasError
            For a temperature, pressure or mount outside what `thermal` allows.

        Examples
        --------
        >>> from solas_mi import Lens
        >>> from solas_mi.optics.paraxial import paraxial
        >>> lens = Lens.load("solas-doublet")
        >>> lens.at() is lens
        True
        >>> round(paraxial(lens.at(60.0), 531.0).efl_mm - paraxial(lens, 531.0).efl_mm, 4)
        0.0144
        """
        return thermal.lens_at(self, temperature_c, pressure_kpa, mount)

    def check_wavelength(self, wavelength_nm: float) -> float:
        """A wavelength every glass of the lens takes.

        Parameters
        ----------
        wavelength_nm : float
            The wavelength (nm).

        Returns
        -------
        float
            `wavelength_nm` as a float.

        Raises
        ------
        SolasError
            For a value that is not a positive number, or one outside a glass's data range.
        """
        if (not isinstance(wavelength_nm, (int, float, np.integer, np.floating)) or isinstance(wavelength_nm, bool)
                or not math.isfinite(wavelength_nm) or wavelength_nm <= 0):
            raise SolasError(f"wavelength {wavelength_nm!r} nm must be a positive number")
        self.indices(float(wavelength_nm))
        return float(wavelength_nm)

    @property
    def primary_wavelength(self) -> float:
        """The middle design wavelength (nm)."""
        return sorted(self.wavelengths_nm)[len(self.wavelengths_nm) // 2]
