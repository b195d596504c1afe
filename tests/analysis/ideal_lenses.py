"""Lenses of the analysis tests: ideal thin lenses (`focal_length` on a flat stop), whose MTF, defocus,
spots and wavefronts have closed forms."""

import math

from solas_mi.optics.lens import Lens

WL = 550.0  # nm


def ideal_lens(f: float = 100.0, f_number: float = 32.0, defocus_mm: float = 0.0, field: float = 5.0) -> Lens:
    """An ideal thin lens of focal length `f` (mm) as its own stop of diameter f/N, the image plane
    `defocus_mm` behind its focus, one wavelength (WL)."""
    return Lens.from_dict(
        {
            "name": "ideal",
            "wavelengths_nm": [WL],
            "field_deg": field,
            "surface": [
                {"radius": 0.0, "thickness": f + defocus_mm, "diameter": f / f_number, "stop": True, "focal_length": f}
            ],
        }
    )


def numerical_aperture(f: float, f_number: float) -> float:
    """sin of the rim ray's angle behind an ideal lens (the ray from height f/(2N) to the focus)."""
    r = f / f_number / 2.0
    return r / math.hypot(r, f)
