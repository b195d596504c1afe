"""The colour correction matrix: white-balanced camera channels → the image's linear RGB.

The sensor's channel responses: a site of filter f collects, per unit of the image's channel c,
    S[f, c] = Q[f, c] λ_c
(`SensorModel.effective_qe`: η_f for the channels c the filter passes and 0 elsewhere in the scalar
model — R, G, B one each, clear all three — or a QE curve's photon-weighted mean over channel c's
band, cross-talk included; times photons per joule, ∝ λ_c, the channel's wavelength; the common
factor A t K / (h c y_sat) drops out).
With S the rows of the three demosaiced channels, D the daylight white-balance gains (`white`) and
w = (D S 1)_ref the balanced level of a white of 1, the matrix from the sensor is

    M = w · P (D S P)⁺

(⁺: pseudo-inverse) with P = I for three filters, so M D S x = w x: a neutral stays neutral at the
camera's own level, and M = I for a sensor whose filters each pass one channel (an ideal sensor, the
RGB Bayer patterns here). RCCB: the clear row is η_c (λ_r R + λ_g G + λ_b B), so M recovers G.
RCCC has two signals, red and clear: P = [[1, 0], [0, 1], [0, 1]] takes G = B, and the frame shows
red and the grey of green and blue (exact for greys and for the red channel).
"""

import numpy as np

from ..errors import SolasError
from ..sensor.cfa import FILTERS
from ..sensor.chain import SensorChain
from ..sensor.model import SensorModel
from .black import GAIN_MAX
from .demosaic import slots


def responses(model: SensorModel | SensorChain) -> np.ndarray:
    """S (3 × 3): the response of each demosaiced channel's filter to each image channel."""
    qe = model.effective_qe()
    lam = np.asarray(model.channel_wavelengths_nm)
    return np.array([qe[FILTERS.index(f)] * lam for f in slots(model.cfa)[1]])


def sensor_matrix(model: SensorModel | SensorChain, gains: np.ndarray) -> np.ndarray:
    """M = w · P (D S P)⁺ for the sensor's responses S and the daylight gains `gains` (one per channel)."""
    balanced = np.diag(gains) @ responses(model)
    basis = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 1.0]]) if model.cfa == "RCCC" else np.eye(3)
    level = float((balanced @ np.ones(3))[1])
    return level * basis @ np.linalg.pinv(balanced @ basis)


def check_matrix(values) -> np.ndarray:
    """A given 3 × 3 matrix of numbers within ±GAIN_MAX (rows: output R, G, B)."""
    sequence = (list, tuple, np.ndarray)
    given = (
        isinstance(values, sequence)
        and len(values) == 3
        and all(
            isinstance(row, sequence)
            and len(row) == 3
            and all(isinstance(v, (int, float, np.number)) and not isinstance(v, (bool, np.bool_)) for v in row)
            for row in values
        )
    )
    matrix = np.array(values, dtype=np.float64) if given else np.empty(0)
    if not given or not np.all(np.abs(matrix) <= GAIN_MAX):
        raise SolasError(f"colour correction matrix {values!r} must be 3 rows of 3 numbers within ±{GAIN_MAX:g}")
    return matrix


def correct(image: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """`matrix` applied to each pixel of an (H, W, 3) image."""
    return image @ matrix.T
