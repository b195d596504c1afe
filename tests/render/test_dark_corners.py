"""A render whose film reaches past the lens's image shows the dark corners a real camera shows, with
a warning naming the field the lens covers (it was refused: 'the lens does not image that field')."""
import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.optics.illumination import image_scales
from solas_mi.render.image import render_image
from solas_mi.render.spec import RenderSpec


def test_a_film_wider_than_the_doublet_s_image_has_dark_corners():
    """38.4 × 28.8 mm of film (24 mm to a corner) behind the doublet, whose light ends at 9.65°: its
    chief rays are blocked from a smaller field on, which the warning names."""
    with pytest.warns(UserWarning, match=r"pass every aperture up to field ([\d.]+) deg \(image height ([\d.]+) mm\)") as w:
        r = render_image(Lens.load("solas-doublet"), "scenes/images/rocket.png",
                         RenderSpec(sensor=(24, 32), pitch_um=1200, spp=4))
    import re

    field, height = map(float, re.search(r"up to field ([\d.]+) deg \(image height ([\d.]+) mm",
                                         str(w[0].message)).groups())
    assert 3.0 < field < 9.7 and height < 24.0
    a = np.asarray(r.image)
    assert np.isfinite(a).all()
    assert np.all(a[:2, :2] == 0) and np.all(a[-2:, -2:] == 0)  # the corners: no light
    assert a[8:16, 12:20].sum() > 0


def test_image_scales_end_where_the_chief_rays_do():
    """Within the image the table is today's; past it, it stops at the last field with a chief ray."""
    lens = Lens.load("cooke-triplet")
    h, radial, tangential = image_scales(lens, 25.0, 587.5618)
    with pytest.warns(UserWarning, match=r"pass every aperture up to field [\d.]+ deg"):
        h_far, radial_far, tangential_far = image_scales(lens, 40.0, 587.5618)
    assert h_far[-1] < 40.0 and h_far[-1] > h[-1]
    assert np.all(np.isfinite(radial_far)) and np.all(radial_far > 0) and np.all(tangential_far > 0)
    assert np.interp(20.0, h_far, radial_far) == pytest.approx(np.interp(20.0, h, radial), rel=1e-3)
