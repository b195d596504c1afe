"""The geometric MTF and MTF50 of the lens as built at fields anywhere in the field (x, y degrees; no half of it
mirrored), from the rays that `psf.as_built.field_hits` lands on its (possibly tilted) image plane: the OTF of
their spot (`otf.spot_otf`) along the field's direction (tangential: from the axis toward the field, +y on
axis) and across it (sagittal). Without diffraction: the lens as built has no pupil function yet.
Lengths in mm, frequencies in cycles/mm, wavelengths in nm."""

from __future__ import annotations

import numpy as np

from ..metrics.mtf import mtf50
from ..psf.as_built import field_hits
from .inputs import cutoff_cy_mm
from .mtf_field import MTF50_SAMPLES
from .otf import spot_otf

RAYS = 64  # rays per side of each field's grid across its beam


def directions(field_deg) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors (x, y) in the image plane of a field's tangential and sagittal directions."""
    f = np.asarray(field_deg, dtype=np.float64)
    norm = np.hypot(*f)
    tangential = f / norm if norm > 0 else np.array([0.0, 1.0])
    return tangential, np.array([tangential[1], -tangential[0]])


def geometric_mtf(lens, field_deg, wavelength_nm: float, freq_cy_mm, rays: int = RAYS) -> np.ndarray:
    """|OTF| (2, F) [tangential, sagittal] at `freq_cy_mm` of the spot of field `field_deg` (x, y degrees)."""
    hits, _ = field_hits(lens, field_deg, wavelength_nm, rays)
    x, y = hits.x - hits.chief_xy[0], hits.y - hits.chief_xy[1]
    freq = np.asarray(freq_cy_mm, dtype=np.float64)
    return np.array([np.abs(spot_otf(x * u[0] + y * u[1], hits.power, freq)) for u in directions(field_deg)])


def mtf50_across_field(lens, field_deg, wavelength_nm: float, rays: int = RAYS) -> np.ndarray:
    """MTF50 (n, 2) cycles/mm [tangential, sagittal] of the geometric MTF at each of `field_deg` (n, 2) degrees;
    NaN where it does not fall to 1/2 below the diffraction cut-off."""
    freq = np.linspace(0.0, cutoff_cy_mm(lens, wavelength_nm), MTF50_SAMPLES)
    out = [
        [mtf50(m, freq) for m in geometric_mtf(lens, f, wavelength_nm, freq, rays)]
        for f in np.reshape(field_deg, (-1, 2))
    ]
    return np.array(out, dtype=float)


__all__ = ["RAYS", "directions", "geometric_mtf", "mtf50_across_field"]
