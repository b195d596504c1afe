"""A glass melted off its catalogue values: n_d and V_d moved by (Δn_d, ΔV_d), as a tolerance on index
and Abbe number means (`Glass.melt`, `tolerance`).

The model: the whole dispersion curve moves so that n_d and V_d take their new values and the relative
partial dispersions P_x,y = (n_x − n_y)/(n_F − n_C) stay the catalogue's,

    n'(λ) = n_d' + s (n(λ) − n_d),   n_d' = n_d + Δn_d,   s = [(n_d' − 1)/V_d'] / [(n_d − 1)/V_d],

V_d' = V_d + ΔV_d, n_d and V_d from the glass's own formula at the d, F and C lines. A melt changes the
glass's dispersion in scale only; its thermal data (dn/dT) and expansion stay the catalogue's. A model
glass (n_d / V_d) melted is the model glass of the new values, which this formula also gives.
"""

from __future__ import annotations

from dataclasses import replace
from functools import lru_cache


@lru_cache(maxsize=256)
def terms(glass) -> tuple[float, float]:
    """(offset, scale) of a melted `glass` (`glass.melt` = (Δn_d, ΔV_d)): n'(λ) = offset + scale · n(λ)."""
    delta_nd, delta_vd = glass.melt
    nd, vd = replace(glass, melt=(), environment=None).abbe()
    new_nd, new_vd = nd + delta_nd, vd + delta_vd
    scale = ((new_nd - 1.0) / new_vd) / ((nd - 1.0) / vd)
    return new_nd - scale * nd, scale


__all__ = ["terms"]
