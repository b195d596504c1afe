"""The one annulus definition (metrics.annuli): r/R with R the centre-to-corner distance."""

import math

import numpy as np

from solas_mi.metrics.annuli import annulus_map


def test_annulus_map_follows_the_automotive_annuli():
    rings = annulus_map(240, 320)
    assert rings[120, 160] == 0 and rings[0, 0] == 2 and rings[-1, -1] == 2
    y, x = np.mgrid[0:240, 0:320]
    r = np.hypot(x - 159.5, y - 119.5) / math.hypot(160, 120)  # R: centre to the image's corner
    assert np.array_equal(rings, np.where(r < 0.24, 0, np.where(r < 0.6, 1, 2)))
