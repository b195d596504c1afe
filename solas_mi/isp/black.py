"""Black level: the RAW's digital numbers → the signal above black, as a fraction of the sensor's
saturation signal.

    s = (y − black) / y_sat,    y_sat = min(K · full well, white − black)

(K the conversion gain in DN/e⁻; the well or the ADC, whichever fills first, saturates the pixel), so
1.0 is a saturated pixel. An HDR sensor's RAW is first decompanded (`sensor.compander`): y − black is its
merged linear signal, y_sat that of its last readout at saturation (`sensor.chain`). Without this stage the RAW is only scaled, s = y / y_sat, and the black level
stays in the signal (a raised floor in the frame)."""

import numpy as np

from ..sensor.chain import SensorChain
from ..sensor.model import SensorModel

# the largest factor a later stage may apply (a white-balance gain, a colour matrix entry): one DN above black
# is at least 1 / 65535 of the signal (a 16-bit ADC's range), so past this factor every pixel above black
# saturates the frame (and the values stay far inside float64's range)
GAIN_MAX = 65536.0


def saturation_dn(model: SensorModel | SensorChain) -> float:
    """y_sat: the signal above black (DN) of a saturated pixel."""
    return model.saturation_dn


def decompanded_through(model: SensorModel | SensorChain) -> list | None:
    """The compander's knee points (merged code, output code) the RAW is decompanded through; None without."""
    compander = model.compander if isinstance(model, SensorChain) else None
    return None if compander is None else compander.describe()["knees"]


def subtract_black(raw: np.ndarray, model: SensorModel | SensorChain, *, enabled: bool = True) -> np.ndarray:
    """The signal (float64, 1.0 = saturation) of a RAW frame in DN, linear (an HDR sensor's decompanded,
    `SensorChain.linear_dn`); `enabled=False` keeps the black level."""
    return (model.linear_dn(raw) + (0 if enabled else model.black_level_dn)) / saturation_dn(model)
