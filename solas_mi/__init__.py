"""solas-mi: physically based lens simulation for automotive camera images.

The package follows the data: `optics` (lens files, glass, paraxial data, the Float64 tracer) →
`psf` (PSF methods and PSF grids) → `convolution` (spatially variant blur of an image); `optics` →
`render` (the lens in Mitsuba, the direct spectral render); images → `metrics` (e-SFR, MTF50,
natural-scene SFR); `validation` checks the two engines against each other. `cli` composes each
stage's `commands`.

Reproduces and goes past: D. Jakab, J. Barthel, A. Braun, R. Mohandas, B. M. Deegan, M. Kumbham,
D. Molloy, F. Collins, A. Scanlan and C. Eising, "SOLAS: Superpositioning an Optical Lens in
Automotive Simulation", IS&T International Symposium on Electronic Imaging, Autonomous Vehicles and
Machines, 2025 (its BK7/F2 doublet, PSF grids, patch convolution and annulus MTF50).
"""

from __future__ import annotations

from . import render  # noqa: F401  (registers the render stage's PSF method "render": `psf.registry`)
from .errors import SolasError
from .lazy import lazy_exports
from .resources import installed_version as _installed_version

__all__ = ["Lens", "SolasError", "mitsuba", "paraxial", "spot"]
__version__ = _installed_version()

# `from solas_mi import Lens, paraxial, spot`; PSFs: `from solas_mi.psf import psf, psf_grid, PSFGrid`;
# Mitsuba with the plugins: `mi = solas_mi.mitsuba(); mi.render(mi.load_file("scene.xml"))`
__getattr__ = lazy_exports(
    __name__,
    {"Lens": ".optics.lens", "paraxial": ".optics.paraxial", "spot": ".optics.spot", "mitsuba": ".render.mitsuba"},
)
