"""Demosaicing methods by name over the colour-demosaicing package (Colour Developers), one
dispatcher routing each method's own options, as colour-science's `*_METHODS` mappings do.

The package demosaics Bayer arrays (RGGB and its turns). The automotive patterns go through it with
the clear sites in the green sites' place: RCCB as RGGB, giving the channels (R, C, B); RCCC as
RGGB, giving (R, C, C) — its "B" sites are clear too, so the third channel is a second estimate of
the clear signal. `slots` names the filter behind each output channel; the colour correction matrix
(`ccm`) then recovers green from clear (RCCB), or red and grey from (R, C) (RCCC).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import SolasError

# pattern → (the Bayer pattern the demosaicer is given, the filter behind each output channel)
BAYER = {"RCCB": ("RGGB", "RCB"), "RCCC": ("RGGB", "RCC")}


def slots(pattern: str) -> tuple[str, str]:
    """(Bayer pattern, filters of the three output channels) of a CFA pattern."""
    return BAYER.get(pattern, (pattern, "RGB"))


@dataclass(frozen=True)
class DemosaicMethod:
    """A demosaicing method: the colour-demosaicing function's name, its own options (each a switch, true
    or false), a reference."""

    name: str
    function: str
    options: tuple[str, ...]
    reference: str

    def compute(self) -> Callable:
        with warnings.catch_warnings():  # its modules import scipy.ndimage.filters, deprecated in SciPy
            warnings.simplefilter("ignore", DeprecationWarning)
            import colour_demosaicing

        return getattr(colour_demosaicing, self.function)


METHODS = {m.name: m for m in (
    DemosaicMethod("bilinear", "demosaicing_CFA_Bayer_bilinear", (),
                   "bilinear interpolation of each channel's sites"),
    DemosaicMethod("Malvar2004", "demosaicing_CFA_Bayer_Malvar2004", (),
                   "Malvar, He and Cutler 2004, high-quality linear interpolation (ICASSP)"),
    DemosaicMethod("Menon2007", "demosaicing_CFA_Bayer_Menon2007", ("refining_step",),
                   "Menon, Andriani and Calvagno 2007, directional filtering and a posteriori decision (IEEE TIP)"),
)}
DEFAULT_METHOD = "Malvar2004"


def check_method(name: str, options: dict | None = None) -> DemosaicMethod:
    """The method `name`, its `options` checked against its own (SolasError naming what is allowed)."""
    if not isinstance(name, str) or name not in METHODS:
        raise SolasError(f"demosaicing method {name!r} must be one of {', '.join(METHODS)}")
    method = METHODS[name]
    options = {} if options is None else options
    if not isinstance(options, dict):
        raise SolasError(f"demosaicing options {options!r} must be a table of option = true/false "
                         f"({name}'s options: {', '.join(method.options) or 'none'})")
    unknown = sorted(set(options) - set(method.options))
    if unknown:
        raise SolasError(f"demosaicing method {name!r} takes no option {', '.join(unknown)} "
                         f"(its options: {', '.join(method.options) or 'none'})")
    for key, value in options.items():
        if not isinstance(value, bool):
            raise SolasError(f"demosaicing option {key} = {value!r} must be true or false (a switch of {name})")
    return method


MINIMUM_FRAME = 2  # rows and columns: one whole 2×2 tile of the pattern, a site of every filter


def check_frame(shape: tuple[int, ...], what: str) -> None:
    """SolasError unless a mosaic of `shape` holds a whole CFA tile (every filter's sites); `what` needs it."""
    if len(shape) != 2 or min(shape) < MINIMUM_FRAME:
        size = "x".join(str(n) for n in shape[::-1])
        raise SolasError(f"{what} needs a frame of at least {MINIMUM_FRAME}x{MINIMUM_FRAME} pixels (one whole tile of "
                         f"the colour filter array), got {size}")


def demosaic(mosaic: np.ndarray, pattern: str, method: str = DEFAULT_METHOD, **options) -> np.ndarray:
    """The three channels (H, W, 3; filters `slots(pattern)[1]`) of a one-channel mosaic of `pattern`."""
    function = check_method(method, options).compute()
    check_frame(mosaic.shape, f"demosaicing ({method})")
    bayer, _ = slots(pattern)
    return np.asarray(function(mosaic, bayer, **options), dtype=np.float64)
