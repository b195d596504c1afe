"""Demosaicing methods by name (`METHODS`, a `solas_mi.registry.Registry`) over the colour-demosaicing
package (Colour Developers), one dispatcher routing each method's own options, as colour-science's
`*_METHODS` mappings do.

The package demosaics Bayer arrays (RGGB and its turns). The automotive patterns go through it with
the clear sites in the green sites' place: RCCB as RGGB, giving the channels (R, C, B); RCCC as
RGGB, giving (R, C, C) — its "B" sites are clear too, so the third channel is a second estimate of
the clear signal. `slots` names the filter behind each output channel; the colour correction matrix
(`ccm`) then recovers green from clear (RCCB), or red and grey from (R, C) (RCCC).
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import SolasError
from ..registry import Entry, Option, Registry

# pattern → (the Bayer pattern the demosaicer is given, the filter behind each output channel)
BAYER = {"RCCB": ("RGGB", "RCB"), "RCCC": ("RGGB", "RCC")}


def slots(pattern: str) -> tuple[str, str]:
    """(Bayer pattern, filters of the three output channels) of a CFA pattern."""
    return BAYER.get(pattern, (pattern, "RGB"))


DEFAULT_METHOD = "Malvar2004"
METHODS = Registry("demosaicing method", default=DEFAULT_METHOD)


def _package():
    """The colour-demosaicing package, imported on first use (it loads SciPy)."""
    with warnings.catch_warnings():  # its modules import scipy.ndimage.filters, deprecated in SciPy
        warnings.simplefilter("ignore", DeprecationWarning)
        import colour_demosaicing

    return colour_demosaicing


@METHODS.register("bilinear", summary="bilinear interpolation of each channel's sites")
def _bilinear(mosaic, bayer):
    return _package().demosaicing_CFA_Bayer_bilinear(mosaic, bayer)


@METHODS.register(
    "Malvar2004",
    summary="high-quality linear interpolation: bilinear corrected by the other channels' gradients",
    reference="Malvar, He and Cutler 2004 (ICASSP)",
)
def _malvar2004(mosaic, bayer):
    return _package().demosaicing_CFA_Bayer_Malvar2004(mosaic, bayer)


@METHODS.register(
    "Menon2007",
    summary="directional filtering and a posteriori decision",
    reference="Menon, Andriani and Calvagno 2007 (IEEE TIP)",
    options=(
        Option(
            "refining_step",
            bool,
            True,
            "a switch of Menon2007: refine the decided estimate",
            label="demosaicing option refining_step =",
        ),
    ),
)
def _menon2007(mosaic, bayer, **options):
    return _package().demosaicing_CFA_Bayer_Menon2007(mosaic, bayer, **options)


def check_method(name: str, options: dict | None = None) -> Entry:
    """The method `name`, its `options` checked against its own (SolasError naming what is allowed)."""
    method = METHODS.get(name)
    options = {} if options is None else options
    if not isinstance(options, dict):
        raise SolasError(
            f"demosaicing options {options!r} must be a table of option = true/false "
            f"({name}'s options: {', '.join(o.name for o in method.options) or 'none'})"
        )
    METHODS.options(name, options, strict=True)
    return method


MINIMUM_FRAME = 2  # rows and columns: one whole 2×2 tile of the pattern, a site of every filter


def check_frame(shape: tuple[int, ...], what: str) -> None:
    """SolasError unless a mosaic of `shape` holds a whole CFA tile (every filter's sites); `what` needs it."""
    if len(shape) != 2 or min(shape) < MINIMUM_FRAME:
        size = "x".join(str(n) for n in shape[::-1])
        raise SolasError(
            f"{what} needs a frame of at least {MINIMUM_FRAME}x{MINIMUM_FRAME} pixels (one whole tile of "
            f"the colour filter array), got {size}"
        )


def demosaic(mosaic: np.ndarray, pattern: str, method: str = DEFAULT_METHOD, **options) -> np.ndarray:
    """The three channels (H, W, 3; filters `slots(pattern)[1]`) of a one-channel mosaic of `pattern`."""
    function = check_method(method, options).function
    check_frame(mosaic.shape, f"demosaicing ({method})")
    bayer, _ = slots(pattern)
    return np.asarray(function(mosaic, bayer, **options), dtype=np.float64)
