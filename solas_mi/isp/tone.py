"""The tone curve: linear values (1.0 = the top of the output range) → encoded [0, 1] → 8 bits.

The curves are `CURVES` (a `solas_mi.registry.Registry`: each curve's function of the clipped values, its
own options, its formula as summary). Values are clipped to [0, 1] first (highlights past saturation and
negative values of the colour correction), then rounded to 8 bits."""
import numpy as np

from ..imageio import srgb_encode
from ..registry import Option, Registry

DEFAULT_CURVE = "srgb"
CURVES = Registry("tone curve", default=DEFAULT_CURVE)
GAMMA = Option("gamma", float, 2.2, "the γ of x^(1/γ)", minimum=0, above=True, label="tone gamma")


@CURVES.register("srgb", summary="the sRGB OETF: 12.92 x below 0.0031308, 1.055 x^(1/2.4) − 0.055 above",
                 reference="IEC 61966-2-1")
def _srgb(x):
    return srgb_encode(x)


@CURVES.register("gamma", options=(GAMMA,), summary="x^(1/γ) for a given γ")
def _gamma(x, gamma):
    return np.power(x, 1.0 / gamma)


@CURVES.register("none", summary="the linear values as they are")
def _none(x):
    return x


def check_curve(curve: str, gamma: float) -> None:
    CURVES.get(curve)
    GAMMA.check(gamma)


def encode(linear: np.ndarray, curve: str = CURVES.default, gamma: float = GAMMA.default) -> np.ndarray:
    """Encoded values in [0, 1] of linear values through `curve`."""
    check_curve(curve, gamma)
    return CURVES[curve].function(np.clip(linear, 0.0, 1.0), **CURVES.options(curve, {GAMMA.name: gamma}))


def to_8bit(encoded: np.ndarray) -> np.ndarray:
    """uint8 codes of encoded values in [0, 1] (nearest code)."""
    return np.round(np.clip(encoded, 0.0, 1.0) * 255.0).astype(np.uint8)
