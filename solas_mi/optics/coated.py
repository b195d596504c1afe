"""A coated surface's transmittance inside the tracer (`tracer.trace(fresnel=True)`; its reflectance for the
ghost paths, `ghost_trace`): the coating's
unpolarised transmittance per wavelength and angle, bilinear in a table of the transfer matrix
(`coating.transmittance_table`) for Dr.Jit arrays of any family, the matrix itself for a Python float ray
(Mitsuba's scalar variants), an ideal coating's constant."""

from __future__ import annotations

from functools import lru_cache

from ..llvm import import_drjit
from . import coating

dr = import_drjit()


def coating_transmittance(c: coating.Coating, before, after, wavelength_um, ftype, reflect: bool = False):
    """cos θ → the unpolarised transmittance (with `reflect`: reflectance) of coating `c` for light from
    medium `before` into `after` at `wavelength_um` (µm), in the array type `ftype`: an ideal coating's
    constant; else bilinear in `coating.transmittance_table` (a Python float: the transfer matrix itself)."""
    if c.reflectance is not None:
        return lambda cosi: c.reflectance if reflect else 1.0 - c.reflectance
    if ftype is float:
        nm = 1000.0 * wavelength_um

        def matrix(cosi):
            power = c.power(before.index(nm), after.index(nm), nm, abs(cosi))
            return float(power.reflectance if reflect else power.transmittance)

        return matrix
    lo, step, count, values = _table(c, before, after, reflect)
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
def _table(c: coating.Coating, before, after, reflect: bool):
    """`coating.transmittance_table`, kept per coating, media and quantity."""
    return coating.transmittance_table(c, before, after, reflect)
