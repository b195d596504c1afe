"""The fisheye rendered directly through its lens geometry: an equidistant environment image of dots
at 0…90° lands where the Float64 tracer's real chief rays land (distortion from the optics alone)."""

import numpy as np
import pytest

from solas_mi import Lens, SolasError
from solas_mi.optics.pupil import chief_rays
from solas_mi.render.image import render_image

STEP_DEG = 0.5  # degrees per texel of the equidistant input
FOV_DEG = 95.75  # its width spans ±FOV_DEG: 383 texels, texel 191 centred on the axis
PITCH_UM = 300.0
SENSOR = 100  # pixels square: ±15 mm, past the 14.0 mm image height of 90°


def dot_image(fields_deg) -> np.ndarray:
    """Equidistant image with one texel lit at each field (degrees; polar fields = equidistant)."""
    n = int(round(2 * FOV_DEG / STEP_DEG))
    img = np.zeros((n, n), np.float32)
    for fx, fy in fields_deg:
        img[n // 2 - int(round(fy / STEP_DEG)), n // 2 + int(round(fx / STEP_DEG))] = 1.0
    return img


def test_dots_land_on_the_chief_rays_out_to_90_degrees():
    lens = Lens.load("nikkor-fisheye")
    fields = np.array([[0.0, 0.0], [0.0, 45.0], [0.0, 75.0], [0.0, 90.0], [90.0, 0.0], [-63.5, -63.5]])
    r = render_image(
        lens,
        dot_image(fields),
        sensor=(SENSOR, SENSOR),
        pitch_um=PITCH_UM,
        spp=256,
        response="mono:587.5618",
        fov_deg=FOV_DEG,
        mapping="equidistant",
        variant="llvm_ad_spectral",
    )
    img = r.image[..., 0].astype(np.float64)
    xy = chief_rays(lens, fields, np.full(len(fields), 587.5618)).image_xy
    pitch = PITCH_UM * 1e-3
    rows, cols = np.indices(img.shape)
    for (fx, fy), (hx, hy) in zip(fields, xy):
        col, row = SENSOR / 2 - 0.5 + hx / pitch, SENSOR / 2 - 0.5 - hy / pitch
        near = (np.abs(rows - row) <= 4) & (np.abs(cols - col) <= 4)
        w = np.where(near, img, 0.0)
        assert w.sum() > 0, f"no light from the dot at ({fx:g}, {fy:g}) deg"
        found = np.array([(w * cols).sum(), (w * rows).sum()]) / w.sum()
        print(f"dot ({fx:g}, {fy:g}) deg: {np.hypot(*(found - [col, row])):.3f} px from its chief ray")
        assert np.hypot(*(found - [col, row])) < 1.0, (fx, fy, found, col, row)
    # the image circle: 90° lands near 14.0 mm, nowhere near a rectilinear lens's infinity
    assert abs(np.hypot(*xy[3]) - 14.0) < 0.1


def test_wide_mappings_are_for_objects_at_infinity_and_named():
    lens = Lens.load("nikkor-fisheye")
    with pytest.raises(SolasError, match="mapping 'fisheye' must be one of"):
        render_image(lens, np.ones((4, 4)), sensor=(4, 4), pitch_um=PITCH_UM, spp=1, mapping="fisheye")


def test_a_3d_scene_through_the_fisheye_lens_camera(tmp_path):
    """Any Mitsuba scene through the fisheye (`render --lens`): small glowing balls 10 m away at 0°,
    60° and 90° off the axis land at the image heights of the tracer's chief rays, within a pixel."""
    from solas_mi.render.stock import render_scene
    from solas_mi.render.user_scene import load

    balls = {
        0.0: (0.0, 0.0, 10.0),
        60.0: (10 * np.sin(np.radians(60)), 0.0, 10 * np.cos(np.radians(60))),
        90.0: (0.0, 10.0, 0.0),
    }
    shapes = "".join(
        f'<shape type="sphere"><point name="center" x="{x}" y="{y}" z="{z}"/><float name="radius" '
        f'value="0.05"/><emitter type="area"><rgb name="radiance" value="100"/></emitter></shape>'
        for x, y, z in balls.values()
    )
    (tmp_path / "balls.xml").write_text(
        '<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="60"/><transform '
        'name="to_world"><lookat origin="0,0,0" target="0,0,1" up="0,1,0"/></transform><film type="hdrfilm">'
        f'<integer name="width" value="{SENSOR}"/><integer name="height" value="{SENSOR}"/></film></sensor>'
        f"{shapes}</scene>"
    )
    lens = Lens.load("nikkor-fisheye")
    scene = load(tmp_path / "balls.xml", "llvm_ad_spectral", lens, pitch_um=PITCH_UM, response="mono:587.5618")
    img = render_scene(scene, 64).image[..., 0].astype(np.float64)
    chief = chief_rays(lens, [[0.0, f] for f in balls], np.full(3, 587.5618))
    heights = np.hypot(*chief.image_xy.T) / (PITCH_UM * 1e-3)
    rows, cols = np.indices(img.shape)
    radius = np.hypot(cols - (SENSOR / 2 - 0.5), rows - (SENSOR / 2 - 0.5))
    for angle, expected in zip(balls, heights):
        ring = np.abs(radius - expected) <= 4
        assert img[ring].sum() > 0.01 * img.sum() / len(balls), f"no light near the {angle:g} deg ring"
        found = (img * ring * radius).sum() / (img * ring).sum()
        assert abs(found - expected) < 1.0, (angle, found, expected)


@pytest.mark.parametrize("fov", [90.0, 100.0, None])
def test_a_rectilinear_input_past_90_degrees_is_refused(fov):
    """tan θ changes sign past 90°: a rectilinear input there would be mirrored, never rendered so."""
    lens = Lens.load("nikkor-fisheye")  # its field: 90°
    with pytest.raises(SolasError, match="rectilinear input spans less than ±90 deg"):
        render_image(lens, np.ones((4, 4)), sensor=(4, 4), pitch_um=PITCH_UM, spp=1, fov_deg=fov, mapping="rectilinear")
