"""Far finite objects: the pupil's power and the chief ray stay right however far the object is
(a cancellation-free solid angle; an aim that converges to the precision a far launch allows)."""

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.optics.pupil import chief_rays
from solas_mi.psf import psf


@pytest.mark.parametrize("distance", [2e8, 5e8, 1e9, 1e12])
def test_transmission_and_chief_ray_of_far_objects(doublet_spec, distance):
    near = dict(doublet_spec, object={"distance": 1e6})
    far = dict(doublet_spec, object={"distance": distance})
    t_near = psf(Lens.from_dict(near), (0, 1), 531.0, normalization="none", size=32).meta["transmission"]
    t_far = psf(Lens.from_dict(far), (0, 1), 531.0, normalization="none", size=32).meta["transmission"]
    assert t_far == pytest.approx(t_near, rel=1e-5)  # was 10–30 % off at 2e8–5e8 mm, refused beyond
    at_infinity = chief_rays(Lens.from_dict(doublet_spec), [[0.0, 1.0]], [531.0]).image_xy[0]
    image = chief_rays(Lens.from_dict(far), [[0.0, 1.0]], [531.0]).image_xy[0]
    assert np.abs(image - at_infinity).max() < 1e-6  # mm: the object is at infinity for this lens


@pytest.mark.parametrize("distance", [1e10, 1e12, 1e14])
def test_psf_of_far_objects_is_the_psf_at_infinity(doublet, distance):
    """The optical path from a far object point is measured from a sphere about it, so no path of the
    object's distance enters the OPD: at 1e12 mm the PSF was 30 % of its peak off (1e14: refused)."""
    from dataclasses import replace

    at_infinity = psf(doublet, (0, 1.4), 531.0, size=96)
    far = psf(replace(doublet, object_distance=distance), (0, 1.4), 531.0, size=96)
    assert np.abs(far.data - at_infinity.data).max() < 1e-4 * at_infinity.data.max()
