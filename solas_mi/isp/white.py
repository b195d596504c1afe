"""White balance: one gain per filter, applied to the mosaic's sites before demosaicing; the reference
filter (G, or C for the clear patterns: the middle demosaiced channel) keeps gain 1.

Where the gains come from (`METHODS`):
- ``daylight``: the sensor's own response to a white (equal R, G, B, the image's white): g_f = r_ref /
  r_f with r_f = η_f Σ λ_c over the channels the filter passes (`ccm.responses`);
- ``grey-world``: the frame averages to grey: g_f = mean_ref / mean_f over each filter's sites;
- ``grey-card``: the same over a box (x0, y0, x1, y1) of pixels holding a grey card;
- ``given``: gains from the user, one per filter of the pattern (the reference's is 1);
- ``none``: gains of 1.
"""
import numpy as np

from ..errors import SolasError
from ..sensor.cfa import FILTERS, site_map
from ..sensor.model import SensorModel
from .ccm import responses
from .demosaic import slots

METHODS = ("daylight", "grey-world", "grey-card", "given", "none")


def reference(pattern: str) -> str:
    return slots(pattern)[1][1]


def _filters(pattern: str) -> list[str]:
    return sorted(set(pattern), key=FILTERS.index)


def daylight_gains(model: SensorModel) -> dict[str, float]:
    """g_f = r_ref / r_f for the sensor's response r_f to a white of 1 in every channel."""
    white = dict(zip(slots(model.cfa)[1], responses(model).sum(axis=1)))
    return {f: white[reference(model.cfa)] / white[f] for f in _filters(model.cfa)}


def measured_gains(signal: np.ndarray, pattern: str, box: tuple[int, int, int, int] | None = None) -> dict[str, float]:
    """Gains that make each filter's mean over `box` (x0, y0, x1, y1; the whole frame when None) that of
    the reference filter."""
    sites = site_map(pattern, signal.shape)
    x0, y0, x1, y1 = box if box is not None else (0, 0, signal.shape[1], signal.shape[0])
    if not (0 <= x0 < x1 <= signal.shape[1] and 0 <= y0 < y1 <= signal.shape[0]) or min(x1 - x0, y1 - y0) < 2:
        raise SolasError(f"grey card box {box!r} must be x0, y0, x1, y1 with 0 <= x0 < x1 <= {signal.shape[1]}, "
                         f"0 <= y0 < y1 <= {signal.shape[0]}, at least 2 pixels each way")
    part, here = signal[y0:y1, x0:x1], sites[y0:y1, x0:x1]
    means = {f: float(part[here == FILTERS.index(f)].mean()) for f in _filters(pattern)}
    if not all(m > 0 for m in means.values()):
        raise SolasError(f"white balance: a filter's mean signal is not above black ({means}); "
                         "no gains can be measured from this region")
    return {f: means[reference(pattern)] / m for f, m in means.items()}


def check_given(gains: dict, pattern: str) -> dict[str, float]:
    """The user's gains: a finite number > 0 for each filter of `pattern`, nothing else."""
    wanted = _filters(pattern)
    if not isinstance(gains, dict) or sorted(gains, key=FILTERS.index) != wanted \
            or not all(isinstance(v, (int, float)) and np.isfinite(v) and v > 0 for v in gains.values()):
        raise SolasError(f"white balance gains {gains!r} must give a number > 0 for each filter of {pattern}: "
                         f"{', '.join(wanted)}")
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
