"""One wavelength per path drawn from a camera response (`solas_mi.render.response`), for the sensors
that look through a lens (in every Mitsuba variant; `tables` holds the lookups). Wavelengths in nm.

A mono variant's rays carry no wavelength: there the response must have one (`render.mitsuba.check_variant`),
the sensors trace the lens at it, and the rays leave with none (`lanes`)."""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np
from solas_mi.plugins.tables import lookup, table

from solas_mi.errors import SolasError
from solas_mi.optics.glass import LINE_D
from solas_mi.render.mitsuba import check_variant

QUANTILES = 4096  # nodes of `WavelengthSampler.sample_quantile`'s inverse CDF (a multiple of 4: the lanes' quarters)


def mono_wavelength(props: mi.Properties, plugin: str) -> float:
    """A plugin's `wavelength` parameter (nm; default the d line, `optics.glass.LINE_D`): the one
    wavelength of a mono variant. SolasError unless positive."""
    value = float(props.get("wavelength", LINE_D))
    if not value > 0:
        raise SolasError(f"{plugin} wavelength {props.get('wavelength')!r} must be positive (nm)")
    return value


def lanes(lam: mi.Float):
    """A ray's wavelengths: `lam` (nm) in all four lanes in a spectral variant, none in a mono one."""
    return mi.Spectrum(lam) if mi.is_spectral else mi.Color0f()


class WavelengthSampler:
    """The response's bins: a bin chosen by its probability, a wavelength uniform inside it."""

    def __init__(self, response) -> None:
        r = response
        check_variant(mi.variant(), r)
        self.distribution = mi.DiscreteDistribution(table(r.probability))
        self.lo, self.hi = table(r.lo_nm), table(r.hi_nm)
        # 1/p(λ): the bin's width over its probability (a line: 1 over its probability)
        self.inverse_pdf = table(np.where(r.hi_nm > r.lo_nm, r.hi_nm - r.lo_nm, 1.0) / r.probability)
        nodes = np.float32(r.sample(np.arange(QUANTILES + 1) / QUANTILES)[0])
        self.quantiles = table(nodes) if bool((r.hi_nm > r.lo_nm).all() and (np.diff(nodes) > 0).all()) else None

    def sample(self, sample1: mi.Float, active=True) -> tuple[mi.Float, mi.UInt32]:
        """A wavelength (nm) and the bin it came from."""
        index, u = self.distribution.sample_reuse(sample1, active)
        lo, hi = lookup(self.lo, index, active), lookup(self.hi, index, active)
        return dr.fma(u, hi - lo, lo), index

    def weight(self, index: mi.UInt32, active=True) -> mi.Float:
        """1/p(λ) of a wavelength of bin `index`."""
        return lookup(self.inverse_pdf, index, active)

    def sample_quantile(self, sample1: mi.Float, active=True) -> tuple[mi.Float, mi.Float]:
        """A wavelength (nm) and its 1/p(λ), without the bins' search: for a continuous response, linear
        between the response's quantiles j/`QUANTILES` (Float32 nodes, strictly increasing), with that
        distribution's own density p = 1/(`QUANTILES` × the node interval) (the response's density
        averaged over each interval: the same wherever an interval lies inside a bin, and an unbiased
        estimate everywhere); with lines (no density), `sample` and `weight`."""
        if self.quantiles is None:
            lam, index = self.sample(sample1, active)
            return lam, self.weight(index, active)
        x = dr.clip(sample1, 0.0, 1.0) * QUANTILES
        j = dr.minimum(mi.UInt32(x), QUANTILES - 1)
        lo, hi = lookup(self.quantiles, j, active), lookup(self.quantiles, j + 1, active)
        return dr.fma(x - mi.Float(j), hi - lo, lo), (hi - lo) * QUANTILES
