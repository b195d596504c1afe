"""Defect-pixel correction: each pixel of the sensor's defect map (its dead and hot pixels, known to the
camera as a calibration map is) takes the mean of its nearest neighbours of the same filter, two pixels away
along the row and the column (every pattern's tile is 2 × 2), leaving out neighbours that are defects too;
a pixel with none keeps its value."""

import numpy as np

STEPS = ((-2, 0), (2, 0), (0, -2), (0, 2))  # the same filter's nearest sites of a 2 × 2 tile


def correct(signal: np.ndarray, defective: np.ndarray | None) -> tuple[np.ndarray, int]:
    """The signal (H, W) with each defect pixel replaced (module docstring), and how many were replaced
    (`defective` None: none)."""
    if defective is None:
        return signal, 0
    height, width = signal.shape
    total, count = np.zeros_like(signal), np.zeros(signal.shape, dtype=np.int64)
    for dy, dx in STEPS:
        rows = slice(max(dy, 0), height + min(dy, 0))
        cols = slice(max(dx, 0), width + min(dx, 0))
        into = (slice(max(-dy, 0), height + min(-dy, 0)), slice(max(-dx, 0), width + min(-dx, 0)))
        good = ~defective[rows, cols]
        total[into] += np.where(good, signal[rows, cols], 0.0)
        count[into] += good
    fixed = defective & (count > 0)
    out = signal.copy()
    out[fixed] = total[fixed] / count[fixed]
    return out, int(np.count_nonzero(fixed))
