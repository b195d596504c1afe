"""A lens at a temperature and air pressure: glass indices by the Schott thermal formula, the air's index,
and the expansion of glass and mount (`lens_at`, which `Lens.at` calls).

Indices and wavelengths. A catalogue's indices are relative to air, and we take them as holding at the
design's conditions, `STANDARD_C` and `STANDARD_KPA` (20 °C, 101.325 kPa: SCHOTT's, and every design
tool's with its environment adjustment off). Inside a lens at temperature T and pressure p every index
stays relative to the air around it (air is 1): a glass's index there is its absolute index at T over
the air's at (T, p). Wavelengths keep naming the light by its wavelength in standard air (the
catalogues' λ), so a sensor's response and a lens file's wavelengths mean the same light at any
temperature; the PSF's diffraction scale takes λ as given, which the air's index change makes at most
1e-4 relative off at −40 … +105 °C and 80 … 110 kPa (far below a PSF's sampling).

The Schott formula (SCHOTT TIE-19, "Temperature Coefficient of the Refractive Index", after Hoffmann,
Jochs and Westenberger 1990), for a glass's data (D0, D1, D2, E0, E1, λ_TK in µm) about its reference
temperature T0 (the vendor's: SCHOTT 20 °C, OHARA 25 °C, HIKARI 23 °C):

    Δn_abs(λ, ΔT) = (n² − 1)/(2n) · (D0 ΔT + D1 ΔT² + D2 ΔT³ + (E0 ΔT + E1 ΔT²)/(λ² − λ_TK²)),  ΔT = T − T0

and the index at T is n_abs(20 °C) + Δn_abs(T − T0) − Δn_abs(20 °C − T0), n_abs(20 °C) = n_rel · n_air(20 °C,
101.325 kPa). The air's absolute index is the formula SCHOTT TIE-19 and the vendors' relative-to-absolute
conversions use (Edlén 1953 for standard air at 15 °C, scaled to T and p):

    n_air(λ, 15 °C, p0) − 1 = 1e-8 (6432.8 + 2949810 λ²/(146 λ² − 1) + 25540 λ²/(41 λ² − 1)),
    n_air(λ, T, p) = 1 + (n_air(λ, 15 °C, p0) − 1) (p/p0) / (1 + 3.4785e-3 (T − 15 °C)).

Expansion (linear, as design tools model it): a glass element's radii, thicknesses, apertures and
aspheric terms scale by 1 + α_glass ΔT (its catalogue's CTE at −30 … +70 °C), an air gap by 1 + α_mount ΔT
(the spacer or housing that holds it, `MOUNTS` or a CTE in 1/K: the lens file's `mount` of the surface
before the gap, else `DEFAULT_MOUNT`, unless a call names one), ΔT = T − 20 °C, from a lens at its own
temperature by the ratio of the two (so going to T and back gives the lens again).
A surface between air and glass takes its glass's α; a cemented one the glass after it; a surface with
air on both sides (a stop, a plane) the mount's, as do its aperture and the image distance. A glass
without thermal data (a model glass, a lens file's own material, a catalogue entry without them) keeps
its absolute index and does not expand: `lens_at` names each such glass in a warning, never silently.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

from ..errors import SolasError

STANDARD_C = 20.0  # °C: the temperature a lens file and a glass catalogue mean by default
STANDARD_KPA = 101.325  # kPa: one standard atmosphere
TEMPERATURE_RANGE_C = (-100.0, 300.0)  # where the glass formula and the air's are taken (°C)
PRESSURE_RANGE_KPA = (0.0, 1000.0)  # vacuum (0) to ten atmospheres
# Mount materials: linear CTE (1/K) near room temperature, typical handbook values (ASM Handbook; aluminium
# 6061-T6, stainless steel 304, Ti-6Al-4V, free-cutting brass, Invar 36); "none": air gaps kept as they are.
MOUNTS = {"aluminium": 23.6e-6, "steel": 17.3e-6, "titanium": 8.6e-6, "brass": 20.5e-6, "invar": 1.3e-6, "none": 0.0}
DEFAULT_MOUNT = "aluminium"
CTE_RANGE = (-1e-4, 1e-3)  # 1/K: a mount CTE given as a number


def check_environment(temperature_c, pressure_kpa) -> tuple[float, float]:
    """(temperature °C, pressure kPa) as floats, or SolasError naming the bad value and the allowed range."""
    for value, what, unit, (lo, hi) in (
        (temperature_c, "temperature", "°C", TEMPERATURE_RANGE_C),
        (pressure_kpa, "pressure", "kPa", PRESSURE_RANGE_KPA),
    ):
        if (
            not isinstance(value, (int, float))
            or isinstance(value, bool)
            or not math.isfinite(value)
            or not lo <= value <= hi
        ):
            raise SolasError(f"{what} {value!r} {unit} must be a number from {lo:g} to {hi:g} {unit}")
    return float(temperature_c), float(pressure_kpa)


def mount_cte(mount) -> float:
    """The CTE (1/K) of a mount: a material of `MOUNTS` or a number (1/K); SolasError otherwise."""
    if isinstance(mount, str) and mount.strip().lower() in MOUNTS:
        return MOUNTS[mount.strip().lower()]
    try:
        value = float(mount)
    except (TypeError, ValueError):
        value = math.nan
    if isinstance(mount, bool) or not CTE_RANGE[0] <= value <= CTE_RANGE[1]:
        raise SolasError(
            f"mount {mount!r} must be a material ({', '.join(MOUNTS)}) or a CTE in 1/K from "
            f"{CTE_RANGE[0]:g} to {CTE_RANGE[1]:g} (e.g. 23.6e-6)"
        )
    return value


def air_index(wavelength_um, temperature_c: float, pressure_kpa: float):
    """The absolute index of dry air (module docstring) at `wavelength_um` (any array type: arithmetic only)."""
    l2 = wavelength_um * wavelength_um
    standard = 1e-8 * (6432.8 + 2949810.0 * l2 / (146.0 * l2 - 1.0) + 25540.0 * l2 / (41.0 * l2 - 1.0))
    return 1.0 + standard * (pressure_kpa / STANDARD_KPA) / (1.0 + 3.4785e-3 * (temperature_c - 15.0))


def absolute_change(thermal: tuple[float, ...], index, wavelength_um, delta_c: float):
    """Δn_abs of the Schott formula over `delta_c` from the reference temperature, for a glass of index
    `index` (the catalogue's at `wavelength_um`) and data `thermal` = (D0, D1, D2, E0, E1, λ_TK µm)."""
    d0, d1, d2, e0, e1, ltk = thermal
    l2 = wavelength_um * wavelength_um
    dt = delta_c
    return (
        (index * index - 1.0)
        / (2.0 * index)
        * (d0 * dt + d1 * dt * dt + d2 * dt * dt * dt + (e0 * dt + e1 * dt * dt) / (l2 - ltk * ltk))
    )


def relative_index(glass, index, wavelength_um, environment: tuple[float, float], constant=float):
    """The index relative to the air around it, at `environment` (°C, kPa), of `glass` whose catalogue index
    at `wavelength_um` is `index` (module docstring); without thermal data, its absolute index held.
    `constant` turns the glass's thermal data and the environment into values of the caller's type
    (`Glass.index_formula`)."""
    temperature, pressure = environment
    absolute = index * air_index(wavelength_um, STANDARD_C, STANDARD_KPA)
    if glass.thermal:
        data = tuple(constant(v) for v in glass.thermal)
        absolute = absolute + (
            absolute_change(data, index, wavelength_um, constant(temperature - glass.reference_c))
            - absolute_change(data, index, wavelength_um, constant(STANDARD_C - glass.reference_c))
        )
    return absolute / air_index(wavelength_um, constant(temperature), constant(pressure))


def _scaled_surface(surface, factor: float, thickness_factor: float):
    """`surface` grown by `factor` (radius, aperture, aspheric and Qbfs terms: z(r) → s·z(r/s)), its
    thickness by `thickness_factor`."""
    aspheric = tuple(a * factor ** (1 - 2 * (i + 2)) for i, a in enumerate(surface.aspheric))
    return replace(
        surface,
        radius=surface.radius * factor,
        thickness=surface.thickness * thickness_factor,
        diameter=surface.diameter * factor,
        aspheric=aspheric,
        qbfs=tuple(q * factor for q in surface.qbfs),
        norm_radius=surface.norm_radius * factor if any(surface.qbfs) else surface.norm_radius,
        form=None if surface.form is None else surface.form.scaled(factor),
        placement=None if surface.placement is None else surface.placement.scaled(factor),
    )


def _glass_cte(glass, mount: float) -> float:
    """α of a medium: its catalogue CTE for a glass that has one; 0 for a glass without; the mount's for air."""
    if glass.kind == "air":
        return mount
    return glass.cte or 0.0


def _mounts(lens, mount) -> list[float]:
    """One mount CTE per surface (the gap after it): `mount` for all, a sequence of one per surface, or (None)
    each surface's own (its lens file's `mount`), `DEFAULT_MOUNT` where it has none."""
    if mount is None:
        return [mount_cte(DEFAULT_MOUNT if s.mount is None else s.mount) for s in lens.surfaces]
    if isinstance(mount, (list, tuple)):
        if len(mount) != len(lens.surfaces):
            raise SolasError(
                f"mount: {len(mount)} values for {len(lens.surfaces)} surfaces; give one per surface "
                "(the gap after it) or one for all"
            )
        return [mount_cte(m) for m in mount]
    return [mount_cte(mount)] * len(lens.surfaces)


def _unthermal(lens) -> list[str]:
    """The names of the lens's glasses that hold their index or their size: no thermal data, or no CTE."""
    media = {g.name: g for g in (lens.object_glass, *(s.glass for s in lens.surfaces)) if g.kind != "air"}
    return sorted(name for name, g in media.items() if not g.thermal or g.cte is None)


def lens_at(lens, temperature_c: float, pressure_kpa: float, mount=None):
    """`lens` at `temperature_c` and `pressure_kpa` (`Lens.at`): the lens itself when both are its own."""
    temperature, pressure = check_environment(temperature_c, pressure_kpa)
    ctes = _mounts(lens, mount)
    if (temperature, pressure) == (lens.temperature_c, lens.pressure_kpa):
        return lens

    def grown(alpha: float) -> float:  # a length at 20 °C is L (1 + α (T − 20 °C)): back and forth is exact
        return (1.0 + alpha * (temperature - STANDARD_C)) / (1.0 + alpha * (lens.temperature_c - STANDARD_C))

    surfaces, before = [], lens.object_glass
    for surface, cte in zip(lens.surfaces, ctes):
        after = surface.glass
        shape_cte = _glass_cte(after if after.kind != "air" else before, cte)
        surfaces.append(_scaled_surface(surface, grown(shape_cte), grown(_glass_cte(after, cte))))
        before = after
    return in_environment(replace(lens, surfaces=tuple(surfaces)), temperature, pressure)


def in_environment(lens, temperature_c: float, pressure_kpa: float):
    """`lens` with its geometry as it is and every medium at `temperature_c` and `pressure_kpa` (a lens file
    that states its temperature and pressure: its prescription holds there)."""
    temperature, pressure = check_environment(temperature_c, pressure_kpa)
    held = _unthermal(lens) if temperature != STANDARD_C else []
    if held:
        warnings.warn(
            f"lens {lens.name} at {temperature:g} °C: {'glasses' if len(held) > 1 else 'glass'} "
            f"{', '.join(held)} without thermal data (Schott formula or CTE) in the catalogue: absolute "
            "index and size held as at 20 °C",
            stacklevel=3,
        )
    return replace(
        lens,
        surfaces=tuple(replace(s, glass=s.glass.at(temperature, pressure)) for s in lens.surfaces),
        object_glass=lens.object_glass.at(temperature, pressure),
        materials=tuple(g.at(temperature, pressure) for g in lens.materials),
        temperature_c=temperature,
        pressure_kpa=pressure,
    )


def metadata(lens) -> dict:
    """{"temperature_c", "pressure_kpa"} of a lens not at 20 °C and 101.325 kPa ({} there: metadata unchanged)."""
    if (lens.temperature_c, lens.pressure_kpa) == (STANDARD_C, STANDARD_KPA):
        return {}
    return {"temperature_c": lens.temperature_c, "pressure_kpa": lens.pressure_kpa}


__all__ = [
    "DEFAULT_MOUNT",
    "MOUNTS",
    "STANDARD_C",
    "STANDARD_KPA",
    "absolute_change",
    "air_index",
    "check_environment",
    "in_environment",
    "lens_at",
    "metadata",
    "mount_cte",
    "relative_index",
]
