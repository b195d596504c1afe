"""Lookup tables and records for the plugins that work in every Mitsuba variant: Dr.Jit arrays gathered
in the JIT variants, NumPy arrays indexed per call in the scalar ones."""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np


def table(values) -> object:
    """A 1-D float table of `values` for `lookup`."""
    values = np.ascontiguousarray(values, dtype=np.float32).ravel()
    return mi.Float(values) if dr.is_jit_v(mi.Float) else values


def lookup(values, index, active=True):
    """values[index] where active, else 0."""
    if dr.is_jit_v(mi.Float):
        return dr.gather(mi.Float, values, index, active)
    return float(values[int(index)]) if active else 0.0


def zeros(cls):
    """A zero-initialised Mitsuba record (`mi.PositionSample3f`, …); `dr.zeros` builds none of them in
    the scalar variants, and a default-constructed one is empty in the JIT variants."""
    return dr.zeros(cls) if dr.is_jit_v(mi.Float) else cls()
