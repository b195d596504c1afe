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
