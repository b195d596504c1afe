"""A coated surface's transmittance inside the tracer (`tracer.trace(fresnel=True)`): the coating's
unpolarised transmittance per wavelength and angle, bilinear in a table of the transfer matrix
(`coating.transmittance_table`) for Dr.Jit arrays of any family, the matrix itself for a Python float ray
(Mitsuba's scalar variants), an ideal coating's constant."""

from __future__ import annotations

from functools import lru_cache

from ..llvm import import_drjit
from . import coating

dr = import_drjit()


def coating_transmittance(c: coating.Coating, before, after, wavelength_um, ftype):
    """cos θ → the unpolarised transmittance of coating `c` between media `before` and `after` at
    `wavelength_um` (µm), in the array type `ftype`: an ideal coating's constant; else bilinear in
    `coating.transmittance_table` (a Python float: the transfer matrix itself)."""
    if c.reflectance is not None:
        return lambda cosi: 1.0 - c.reflectance
    if ftype is float:
        nm = 1000.0 * wavelength_um
        return lambda cosi: float(c.power(before.index(nm), after.index(nm), nm, abs(cosi)).transmittance)
    lo, step, count, values = _table(c, before, after)
    table = ftype(values.ravel())
    utype = dr.uint32_array_t(ftype)
    u = dr.clip((1000.0 * wavelength_um - lo) / step, 0.0, count - 1.000001)
    i = dr.floor(u)
    fu = u - i

    def at(cosi):
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
def _table(c: coating.Coating, before, after):
    """`coating.transmittance_table`, kept per coating and media."""
    return coating.transmittance_table(c, before, after)
