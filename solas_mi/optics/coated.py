"""A coated surface's transmittance or reflectance in a trace (the tracer's `trace(fresnel=True)` weight, the
mesh scene's `coated_dielectric`): the coating's unpolarised value per wavelength and angle, bilinear in a
table of the transfer matrix (`coating.power_table`) for Dr.Jit arrays of any family, the matrix itself for a
Python float ray (Mitsuba's scalar variants), an ideal coating's constant."""

from __future__ import annotations

from functools import lru_cache

from ..llvm import import_drjit
from . import coating

dr = import_drjit()


def coating_power(c: coating.Coating, before, after, ftype, quantity: str = "transmittance"):
    """(wavelength µm, cos θ) → the unpolarised `quantity` (one of `coating.TABLE_QUANTITIES`) of coating `c`
    from medium `before` into `after`, in the array type `ftype`: an ideal coating's constant; else bilinear in
    `coating.power_table`, its table made an array once here (a Python float: the transfer matrix itself)."""
    if c.reflectance is not None:
        value = c.reflectance if quantity == "reflectance" else 1.0 - c.reflectance
        return lambda wavelength_um, cosi: value
    if ftype is float:

        def matrix(wavelength_um, cosi):
            nm = 1000.0 * wavelength_um
            return float(getattr(c.power(before.index(nm), after.index(nm), nm, abs(cosi)), quantity))

        return matrix
    lo, step, count, values = _table(c, before, after, quantity)
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
def _table(c: coating.Coating, before, after, quantity: str):
    """`coating.power_table`, kept per coating, media and quantity."""
    return coating.power_table(c, before, after, quantity)
