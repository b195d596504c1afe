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
    with pytest.warns(
        UserWarning, match=r"pass every aperture up to field ([\d.]+) deg \(image height ([\d.]+) mm\)"
    ) as w:
        r = render_image(
            Lens.load("solas-doublet"), "scenes/images/rocket.png", RenderSpec(sensor=(24, 32), pitch_um=1200, spp=4)
        )
    import re

    field, height = map(
        float, re.search(r"up to field ([\d.]+) deg \(image height ([\d.]+) mm", str(w[0].message)).groups()
    )
    assert 3.0 < field < 9.7 and height < 24.0
    a = np.asarray(r.image)
    assert np.isfinite(a).all()
    assert np.all(a[:2, :2] == 0) and np.all(a[-2:, -2:] == 0)  # the corners: no light
    assert a[8:16, 12:20].sum() > 0


def test_image_scales_end_where_the_chief_rays_do():
    """Within the image the table is today's; past it, it stops at the last field with a chief ray."""
    lens = Lens.load("cooke-triplet")
    h, radial, _tangential = image_scales(lens, 25.0, 587.5618)
    with pytest.warns(UserWarning, match=r"pass every aperture up to field [\d.]+ deg"):
        h_far, radial_far, tangential_far = image_scales(lens, 40.0, 587.5618)
    assert h_far[-1] < 40.0 and h_far[-1] > h[-1]
    assert np.all(np.isfinite(radial_far)) and np.all(radial_far > 0) and np.all(tangential_far > 0)
    assert np.interp(20.0, h_far, radial_far) == pytest.approx(np.interp(20.0, h, radial), rel=1e-3)


def test_the_cooke_triplet_renders_30_degrees_where_its_beam_is_vignetted(tmp_path, capsys):
    """`render-image cooke-triplet --fov-deg 30` was refused ("no real ray … field (31.842, 0)"): at the
    very edge of the fields whose chief ray reaches the stop centre (31.842°; 16.5 % of the beam arrives
    at 31.8°, 7.8 % at 32°) the aim at the centre missed, and chief_rays refused the field although light
    passes. Now a field is refused only where no ray passes the stop: fields packed past that edge get the
    passing ray nearest the centre; the film's image-scale table stays inside the edge, so its footprints
    are positive (a substitute there turned the image height back and rendered everything black); the
    render's centre is the 29° render's (the same on-axis light) within its noise, and its corners, past
    the chief rays, still get light."""
    import math
    import warnings

    from solas_mi.cli import main
    from solas_mi.optics import illumination
    from solas_mi.optics.camera import camera_for
    from solas_mi.optics.pupil import chief_rays

    lens = Lens.load("cooke-triplet")
    wl = lens.primary_wavelength
    camera = camera_for(lens, (24, 32), 30.0)
    corner = 0.5 * camera.pitch_mm * math.hypot(32, 24)
    with pytest.warns(UserWarning, match="pass every aperture up to field"):
        h, radial, tangential = image_scales(lens, corner, wl)
    assert np.all(radial > 0) and np.all(tangential > 0) and np.all(np.diff(h) > 0)
    f0 = math.sqrt(float(illumination._jacobian(lens, np.zeros((1, 2)), wl)[0]))
    edge = illumination._last_chief_tangent(lens, 1.05 * corner / f0, wl) / (1.0 - illumination.EDGE_MARGIN)
    fields = np.degrees(np.arctan(edge * (1.0 + np.arange(-20, 21) * 1e-13)))
    chief = chief_rays(lens, np.stack([fields, np.zeros_like(fields)], -1), np.full(len(fields), wl))
    assert np.isfinite(chief.image_xy).all()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        renders = [
            render_image(lens, np.ones((24, 32, 3), np.float32), sensor=(6, 8), spp=16, fov_deg=f).image[..., 1]
            for f in (29.0, 30.0)
        ]
    centre = [float(r[2:4, 3:5].mean()) for r in renders]
    print(f"centre at 29 and 30 deg: {centre}; corners at 30: {renders[1][[0, 0, -1, -1], [0, -1, 0, -1]]}")
    assert centre[1] == pytest.approx(centre[0], rel=0.1)
    assert np.all(renders[1][[0, 0, -1, -1], [0, -1, 0, -1]] > 0)
    out = tmp_path / "c.exr"
    assert (
        main(
            [
                "render-image",
                "cooke-triplet",
                "scenes/images/rocket.png",
                "--fov-deg",
                "30",
                "--sensor",
                "6x8",
                "--spp",
                "1",
                "-o",
                str(out),
            ]
        )
        == 0
        and out.is_file()
    )
