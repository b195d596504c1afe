"""The tone curve: linear values (1.0 = the top of the output range) → encoded [0, 1] → 8 bits.

- ``srgb``: the sRGB OETF (IEC 61966-2-1): 12.92 x below 0.0031308, 1.055 x^(1/2.4) − 0.055 above;
- ``gamma``: x^(1/γ) for a given γ (default 2.2);
- ``none``: the linear values as they are.
Values are clipped to [0, 1] first (highlights past saturation and negative values of the colour
correction), then rounded to 8 bits."""
import numpy as np

from ..errors import SolasError
from ..imageio import srgb_encode

CURVES = ("srgb", "gamma", "none")


def check_curve(curve: str, gamma: float) -> None:
    if curve not in CURVES:
        raise SolasError(f"tone curve {curve!r} must be one of {', '.join(CURVES)}")
    if not isinstance(gamma, (int, float)) or isinstance(gamma, bool) or not np.isfinite(gamma) or gamma <= 0:
        raise SolasError(f"tone gamma {gamma!r} must be a finite number > 0")


def encode(linear: np.ndarray, curve: str = "srgb", gamma: float = 2.2) -> np.ndarray:
    """Encoded values in [0, 1] of linear values through `curve`."""
    check_curve(curve, gamma)
    x = np.clip(linear, 0.0, 1.0)
    if curve == "srgb":
        return srgb_encode(x)
    return np.power(x, 1.0 / gamma) if curve == "gamma" else x


def to_8bit(encoded: np.ndarray) -> np.ndarray:
    """uint8 codes of encoded values in [0, 1] (nearest code)."""
    return np.round(np.clip(encoded, 0.0, 1.0) * 255.0).astype(np.uint8)
