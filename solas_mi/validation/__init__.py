"""Checks of the engines against each other: the PSF-grid convolution against the direct render, and
the Mitsuba scene against the Float64 tracer.

In the order of the data: `inputs` (the input image on the sensor's grid) → `engines` (both engines
in the same settings and units) → `reference` (the converged render and its noise) → `scores` (errors
against it) → `tables` (results as Markdown / CSV); `crossval` (`solas-mi crossval`: every convolution
case against the reference, with error maps) and `error_vs_time` (`solas-mi report error-vs-time`:
error against run time) drive them, `commands` puts both on the command line. Beside them: `scene_psf`
(geometric PSFs traced through the scene's geometry) and `sheet` (a side-by-side sheet of degraded
images, the SOLAS paper's figure 4 layout).
"""

__all__: list[str] = []  # run from the command line (its `commands`): no Python API of its own
