"""A coated surface's transmittance inside the tracer (`tracer.trace(fresnel=True)`; its reflectance for the
ghost paths, `ghost_trace`, and both for the mesh scene's `coated_dielectric`): the coating's unpolarised
value per wavelength and angle, bilinear in a table of the transfer matrix (`coating.transmittance_table`) for
Dr.Jit arrays of any family, the matrix itself for a Python float ray (Mitsuba's scalar variants), an ideal
coating's constant."""

from __future__ import annotations

from functools import lru_cache, partial

from ..llvm import import_drjit
from . import coating

dr = import_drjit()


def coating_transmittance(c: coating.Coating, before, after, wavelength_um, ftype, reflect: bool = False):
    """cos θ → the unpolarised transmittance (with `reflect`: reflectance) of coating `c` for light from
    medium `before` into `after` at `wavelength_um` (µm), in the array type `ftype`: `coating_power` at that
    wavelength."""
    return partial(coating_power(c, before, after, ftype, reflect), wavelength_um)


def coating_power(c: coating.Coating, before, after, ftype, reflect: bool = False):
    """(wavelength µm, cos θ) → the unpolarised transmittance (with `reflect`: reflectance) of coating `c` for
    light from medium `before` into `after`, in the array type `ftype`: an ideal coating's constant; else
    bilinear in `coating.transmittance_table`, made an array once here (a Python float: the transfer matrix
    itself)."""
    if c.reflectance is not None:
        value = c.reflectance if reflect else 1.0 - c.reflectance
        return lambda wavelength_um, cosi: value
    if ftype is float:

        def matrix(wavelength_um, cosi):
            nm = 1000.0 * wavelength_um
            power = c.power(before.index(nm), after.index(nm), nm, abs(cosi))
            return float(power.reflectance if reflect else power.transmittance)

        return matrix
    lo, step, count, values = _table(c, before, after, reflect)
    table = ftype(values.ravel())
    utype = dr.uint32_array_t(ftype)

    def at(wavelength_um, cosi):
        u = dr.clip((1000.0 * wavelength_um - lo) / step, 0.0, count - 1.000001)
        i = dr.floor(u)
        fu = u - i
        v = dr.clip(dr.abs(cosi) * (coating.TABLE_COS - 1), 0.0, coating.TABLE_COS - 1.000001)
        j = dr.floor(v)
        fv = v - j
        index = utype(i) * coating.TABLE_COS + utype(j)
        corner = [
            dr.gather(ftype, table, index + offset) for offset in (0, 1, coating.TABLE_COS, coating.TABLE_COS + 1)
        ]
        return dr.lerp(dr.lerp(corner[0], corner[1], fv), dr.lerp(corner[2], corner[3], fv), fu)

    return at


@lru_cache(maxsize=64)
def _table(c: coating.Coating, before, after, reflect: bool):
    """`coating.transmittance_table`, kept per coating, media and quantity."""
    return coating.transmittance_table(c, before, after, reflect)
