"""White balance: one gain per filter, applied to the mosaic's sites before demosaicing; the reference
filter (G, or C for the clear patterns: the middle demosaiced channel) keeps gain 1.

Where the gains come from: `METHODS` (a `solas_mi.registry.Registry`), each method a function
(signal above black, sensor model, the `pipeline.ISP`) → gain per filter, with its formula as summary.
"""

import numpy as np

from ..errors import SolasError
from ..registry import Registry
from ..sensor.cfa import FILTERS, site_map
from ..sensor.chain import SensorChain
from ..sensor.model import SensorModel
from .black import GAIN_MAX
from .ccm import responses
from .demosaic import MINIMUM_FRAME, check_frame, slots

DEFAULT_METHOD = "daylight"
METHODS = Registry("white balance method", default=DEFAULT_METHOD)
GIVEN = "given"  # the method of gains the user gives: an ISP writes it as its table of gains, not by name


def reference(pattern: str) -> str:
    return slots(pattern)[1][1]


def _filters(pattern: str) -> list[str]:
    return sorted(set(pattern), key=FILTERS.index)


def daylight_gains(model: SensorModel | SensorChain) -> dict[str, float]:
    """g_f = r_ref / r_f for the sensor's response r_f to a white of 1 in every channel."""
    white = dict(zip(slots(model.cfa)[1], responses(model).sum(axis=1)))
    return {f: white[reference(model.cfa)] / white[f] for f in _filters(model.cfa)}


def check_box(box) -> tuple[int, int, int, int]:
    """A grey card's box: four integers x0, y0, x1, y1 (pixels, columns then rows, end exclusive), at least
    2 pixels each way (`demosaic.MINIMUM_FRAME`: a site of every filter)."""
    whole = (
        isinstance(box, (list, tuple))
        and len(box) == 4
        and all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in box)
    )
    if not whole or box[2] - box[0] < MINIMUM_FRAME or box[3] - box[1] < MINIMUM_FRAME:
        raise SolasError(
            f"isp grey_card = {box!r} must be four integers x0, y0, x1, y1 (pixels, end exclusive) with "
            f"0 <= x0, x0 + {MINIMUM_FRAME} <= x1, 0 <= y0, y0 + {MINIMUM_FRAME} <= y1"
        )
    return tuple(box)


def measured_gains(signal: np.ndarray, pattern: str, box: tuple[int, int, int, int] | None = None) -> dict[str, float]:
    """Gains that make each filter's mean over `box` (x0, y0, x1, y1; the whole frame when None) that of
    the reference filter."""
    if box is None:
        check_frame(signal.shape, "grey-world white balance")
        box = (0, 0, signal.shape[1], signal.shape[0])
    x0, y0, x1, y1 = check_box(box)
    if x1 > signal.shape[1] or y1 > signal.shape[0]:
        raise SolasError(
            f"grey card box {box!r} must be inside the {signal.shape[1]}x{signal.shape[0]} frame: "
            f"x1 <= {signal.shape[1]}, y1 <= {signal.shape[0]}"
        )
    sites = site_map(pattern, signal.shape)
    part, here = signal[y0:y1, x0:x1], sites[y0:y1, x0:x1]
    means = {f: float(part[here == FILTERS.index(f)].mean()) for f in _filters(pattern)}
    if not all(m > 0 for m in means.values()):
        raise SolasError(
            f"white balance: a filter's mean signal is not above black ({means}); "
            "no gains can be measured from this region"
        )
    return {f: means[reference(pattern)] / m for f, m in means.items()}


def check_gains(gains) -> dict:
    """A table of gains, one per filter letter (`cfa.FILTERS`), each a number in (0, GAIN_MAX]; which
    filters it must name is the pattern's (`check_given`)."""
    if (
        not isinstance(gains, dict)
        or not gains
        or not set(gains) <= set(FILTERS)
        or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and 0 < v <= GAIN_MAX for v in gains.values()
        )
    ):
        raise SolasError(
            f"white balance gains {gains!r} must be a table of filter letters ({', '.join(FILTERS)}) "
            f"to numbers in (0, {GAIN_MAX:g}], e.g. {{R = 1.9, G = 1, B = 1.5}}"
        )
    return gains


def check_given(gains: dict, pattern: str) -> dict[str, float]:
    """The user's gains: a number in (0, GAIN_MAX] for each filter of `pattern`, nothing else."""
    wanted = _filters(pattern)
    if sorted(check_gains(gains), key=FILTERS.index) != wanted:
        raise SolasError(
            f"white balance gains {gains!r} must give a number > 0 for each filter of {pattern}: {', '.join(wanted)}"
        )
    return {f: float(gains[f]) for f in wanted}


def apply_gains(signal: np.ndarray, pattern: str, gains: dict[str, float]) -> np.ndarray:
    """The mosaic with each site times its filter's gain."""
    table = np.ones(len(FILTERS))
    for f, g in gains.items():
        table[FILTERS.index(f)] = g
    return signal * table[site_map(pattern, signal.shape)]


def channel_gains(pattern: str, gains: dict[str, float]) -> np.ndarray:
    """The gains of the three demosaiced channels (their filters, `demosaic.slots`)."""
    return np.array([gains[f] for f in slots(pattern)[1]])


@METHODS.register(
    "daylight",
    summary="the sensor's own response to a white (equal R, G, B, the image's white): "
    "g_f = r_ref / r_f with r_f = η_f Σ λ_c over the channels the filter passes",
)
def _daylight(signal, model, isp):
    return daylight_gains(model)


@METHODS.register("grey-world", summary="the frame averages to grey: g_f = mean_ref / mean_f over each filter's sites")
def _grey_world(signal, model, isp):
    return measured_gains(signal, model.cfa)


@METHODS.register(
    "grey-card", summary="the same over a box (x0, y0, x1, y1) of pixels holding a grey card (`grey_card`)"
)
def _grey_card(signal, model, isp):
    return measured_gains(signal, model.cfa, isp.grey_card)


@METHODS.register(
    GIVEN,
    summary="gains from the user, one per filter of the pattern (the reference's is 1), "
    "written as a table: {R = 1.9, G = 1, B = 1.5}",
    table=True,
)
def _given(signal, model, isp):
    return check_given(isp.white_balance, model.cfa)


@METHODS.register("none", summary="gains of 1")
def _none(signal, model, isp):
    return check_given(dict.fromkeys(set(model.cfa), 1.0), model.cfa)


def named() -> tuple[str, ...]:
    """The methods an ISP names (the others it writes as a table: `GIVEN`)."""
    return tuple(n for n, e in METHODS.items() if not e.extra.get("table"))
