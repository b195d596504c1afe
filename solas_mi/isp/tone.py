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


@CURVES.register(
    "srgb", summary="the sRGB OETF: 12.92 x below 0.0031308, 1.055 x^(1/2.4) − 0.055 above", reference="IEC 61966-2-1"
)
def _srgb(x):
    return srgb_encode(x)


@CURVES.register("gamma", options=(GAMMA,), summary="x^(1/γ) for a given γ")
def _gamma(x, gamma):
    return np.power(x, 1.0 / gamma)


@CURVES.register("none", summary="the linear values as they are")
def _none(x):
    return x


REINHARD_KEY = 0.18  # the "normal key": the frame's log-average luminance goes to middle grey
LOG_FLOOR = 2.0**-24  # δ of the log-average: one code of a 24-bit merged signal, as a fraction of saturation
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Y of linear sRGB (ITU-R BT.709)


@CURVES.register(
    "reinhard",
    summary="for HDR frames: the luminance Y scaled to L = 0.18 Y / Ȳ (Ȳ its "
    "log-average), compressed to L (1 + L / L_w²) / (1 + L) with L_w the frame's largest L, each pixel's "
    "R, G, B scaled alike, then the sRGB OETF",
    reference="Reinhard, Stark, Shirley, Ferwerda, Photographic Tone Reproduction for Digital Images, "
    "SIGGRAPH 2002, eqs. 1-4",
)
def _reinhard(x):
    luminance = x @ LUMINANCE
    mean = np.exp(np.mean(np.log(LOG_FLOOR + luminance))) if luminance.size else 1.0
    scaled = REINHARD_KEY * luminance / mean
    white = max(float(scaled.max(initial=0.0)), LOG_FLOOR)
    display = scaled * (1.0 + scaled / white**2) / (1.0 + scaled)
    ratio = np.divide(display, luminance, out=np.zeros_like(luminance), where=luminance > 0)
    return srgb_encode(x * ratio[..., None])


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
