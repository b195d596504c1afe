"""The core both lens sensors share (`plugins/lens_film.py`): the film's pixels on the image plane,
its crop window, the density of a film point, and one message for a bad pitch."""

import re
import tempfile
from pathlib import Path

import numpy as np
import pytest

import solas_mi
from solas_mi.imageio import image_channels, write_exr
from solas_mi.optics.camera import camera_for
from solas_mi.render.loop import render
from solas_mi.render.mitsuba import load_scene
from solas_mi.render.scene import write_scene

WIDTH, HEIGHT, PITCH_UM = 64, 48, 5.0
CROP = {"crop_offset_x": 32, "crop_offset_y": 8, "crop_width": 32, "crop_height": 24}
SENSORS = ("lens_sensor", "lens_camera")


@pytest.fixture(scope="module")
def mi():
    return solas_mi.mitsuba("llvm_ad_spectral")


def _sensor(mi, plugin, **film):
    return mi.load_dict(
        {"type": plugin, "pitch_um": PITCH_UM, "film": {"type": "hdrfilm", "width": WIDTH, "height": HEIGHT, **film}}
    )


def _grid(n=5):
    u = (np.arange(n) + 0.5) / n
    uu, vv = (a.ravel() for a in np.meshgrid(u, u))
    return uu, vv


@pytest.mark.parametrize("plugin", SENSORS)
def test_film_points_are_the_pixels_on_the_image_plane(mi, plugin, doublet):
    """A pixel centre of the whole film lands at (column + ½ − W/2, H/2 − row − ½) × pitch (row 0 at
    +y); a film point is drawn with density 1/area; the film's bbox in the lens frame is that area."""
    sensor = _sensor(mi, plugin)
    cols, rows = np.array([0, 17, WIDTH - 1]), np.array([0, 30, HEIGHT - 1])
    p = sensor.film_point(mi.Point2f((cols + 0.5) / WIDTH, (rows + 0.5) / HEIGHT))
    pitch = PITCH_UM * 1e-3
    assert np.allclose(np.array(p.x), (cols + 0.5 - WIDTH / 2) * pitch, atol=1e-7)
    assert np.allclose(np.array(p.y), (HEIGHT / 2 - rows - 0.5) * pitch, atol=1e-7)
    assert sensor.pdf_area() == pytest.approx(1.0 / (WIDTH * HEIGHT * pitch**2))
    assert (sensor.width, sensor.height) == (WIDTH, HEIGHT)


@pytest.mark.parametrize("plugin", SENSORS)
def test_crop_window_maps_onto_its_pixels_of_the_whole_film(mi, plugin):
    """A film sample over the crop window lands where the same pixel of the uncropped film does;
    the rendered image is the crop's size and a film point's density one over the crop's area."""
    whole, cropped = _sensor(mi, plugin), _sensor(mi, plugin, **CROP)
    u, v = _grid()
    x0, y0, w, h = (CROP[k] for k in ("crop_offset_x", "crop_offset_y", "crop_width", "crop_height"))
    inside = cropped.film_point(mi.Point2f(u, v))
    same = whole.film_point(mi.Point2f((x0 + u * w) / WIDTH, (y0 + v * h) / HEIGHT))
    assert np.allclose(np.array(inside.x), np.array(same.x), atol=1e-7)
    assert np.allclose(np.array(inside.y), np.array(same.y), atol=1e-7)
    assert (cropped.width, cropped.height) == (w, h)
    assert cropped.pdf_area() == pytest.approx(whole.pdf_area() * WIDTH * HEIGHT / (w * h))


def _ramp_scene(tmp: str, crop: dict, response: str):
    """A lens_sensor scene (solas-mi's scene generator, the doublet) of a grey ramp rising to the right
    and down (0.6 x + 0.4 y, x and y 0 → 1 across the image), the film cropped to `crop` (none: the
    whole film)."""
    lens = solas_mi.Lens.load("solas-doublet")
    x, y = np.meshgrid(np.linspace(0.0, 1.0, WIDTH), np.linspace(0.0, 1.0, HEIGHT))
    path = str(Path(tmp) / "ramp.exr")
    write_exr(path, image_channels((0.6 * x + 0.4 * y).astype(np.float32)))
    xml = write_scene(
        lens,
        tmp,
        path,
        camera_for(lens, (HEIGHT, WIDTH)),
        spp=16,
        response=response,
        fresnel="off",
        name=f"scene{len(crop)}.xml",
    )
    text = xml.read_text()
    ints = "".join(f'<integer name="{k}" value="{v}"/>' for k, v in crop.items())
    xml.write_text(text.replace('<rfilter type="box"/>', ints + '<rfilter type="box"/>'))
    return load_scene(xml, "llvm_ad_spectral")


def _agree(a: np.ndarray, b: np.ndarray, axis: int) -> None:
    """The means of `a` and `b` along `axis` agree within 5 standard errors (from their scatter)."""
    n = a.shape[axis]
    error = np.sqrt((a.var(axis=axis) + b.var(axis=axis)) / n)
    gap = np.abs(a.mean(axis=axis) - b.mean(axis=axis))
    assert np.all(gap < 5 * error + 1e-3), (gap, error)


@pytest.mark.parametrize("engine, spp", [("loop", 64), ("path", 256)])
def test_cropped_render_is_those_pixels_of_the_whole_render(mi, engine, spp):
    """A lens_sensor render cropped to columns 32–63, rows 8–31 equals those pixels of the uncropped
    render, column by column and row by row, within the noise (solas-mi's loop with the 531 nm line;
    Mitsuba's path integrator with an sRGB response, which its hdrfilm can integrate). The old sensor
    drew the whole image squeezed into the crop (0.06 → 0.79 across a ramp whose columns 32–63 span
    0.49 → 0.82)."""
    with tempfile.TemporaryDirectory() as tmp:
        images = []
        for crop in ({}, CROP):
            scene = _ramp_scene(tmp, crop, "mono:531" if engine == "loop" else "srgb")
            if engine == "loop":
                images.append(render(scene, spp, seed=3).image[..., 0])
            else:
                images.append(np.array(mi.render(scene, spp=spp, seed=3))[..., 0])
    whole, cropped = images
    x0, y0, w, h = (CROP[k] for k in ("crop_offset_x", "crop_offset_y", "crop_width", "crop_height"))
    part = whole[y0 : y0 + h, x0 : x0 + w]
    assert cropped.shape == part.shape
    _agree(cropped, part, 0)
    _agree(cropped, part, 1)
    # the ramp shows across the crop both ways: the test can tell a squeezed or shifted image
    assert part[:, -4:].mean() - part[:, :4].mean() > 0.15 and part[-4:].mean() - part[:4].mean() > 0.08


@pytest.mark.parametrize("plugin", SENSORS)
@pytest.mark.parametrize("pitch", [-1.0, 0.0, float("nan"), "wide"])
def test_bad_pitch_has_one_message(mi, plugin, pitch):
    props = {"type": plugin, "pitch_um": pitch}
    with pytest.raises(RuntimeError, match=re.escape(f"{plugin}: pitch_um {pitch!r} must be a positive number (µm)")):
        mi.load_dict(props)
