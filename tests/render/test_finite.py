"""Never a non-finite value: the lens camera's rays past the image circle are finite with weight 0
(an environment map seen through the fisheye, whose film reaches past its image circle, renders with
no NaN), the image writer refuses a NaN or infinite pixel naming the count and the first, and lines
under an hdrfilm are refused with the way out."""

import numpy as np
import pytest

from solas_mi.errors import SolasError


def _fisheye_env_scene(mi, pitch_um):
    env = np.ones((8, 16, 3), dtype=np.float32)
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path"},
            "env": {"type": "envmap", "bitmap": mi.Bitmap(env)},
            "sensor": {
                "type": "lens_camera",
                "lens": "nikkor-fisheye",
                "pitch_um": pitch_um,
                "film": {"type": "hdrfilm", "width": 40, "height": 30},
            },
        }
    )


def test_env_map_through_the_fisheye_past_its_image_circle_has_no_nan(mi):
    scene = _fisheye_env_scene(mi, 1600.0)  # 64 x 48 mm: the corners far past the 180° circle
    sensor = scene.sensors()[0]
    rng = np.random.default_rng(1)
    u = [mi.Float(rng.random(4000).astype(np.float32)) for _ in range(5)]
    ray, weight = sensor.sample_ray(0.0, u[0], mi.Point2f(u[1], u[2]), mi.Point2f(u[3], u[4]))
    weight = np.array(weight)
    assert np.isfinite(np.array(ray.o)).all() and np.isfinite(np.array(ray.d)).all()
    assert 0.05 < (weight[0] > 0).mean() < 0.6  # some rays pass, many are blocked
    image = np.array(mi.render(scene, spp=4, seed=1))
    assert np.isfinite(image).all()
    assert image[0, 0].max() == 0 and image[13:17, 18:22].mean() > 0.5  # the corner dark, the centre lit


@pytest.mark.parametrize("bad, where", [(np.nan, "row 2, column 3"), (np.inf, "row 2, column 3")])
def test_the_writer_refuses_non_finite_pixels(tmp_path, bad, where):
    from solas_mi.imageio import write_exr, write_png

    image = np.zeros((4, 5), dtype=np.float32)
    image[2, 3] = image[3, 4] = bad
    for write in (lambda p: write_exr(p, {"Y": image}), lambda p: write_png(p, image)):
        path = tmp_path / "out.exr"
        with pytest.raises(SolasError, match=f"2 values are NaN or infinite \\(the first at {where}\\)"):
            write(path)
        assert list(tmp_path.iterdir()) == []  # nothing half-written


def test_infinite_allowed_where_said_nan_never(tmp_path):
    from solas_mi.imageio import read_exr, write_exr

    depth = np.array([[1.0, np.inf]], dtype=np.float32)
    write_exr(tmp_path / "depth.exr", {"Z": depth}, infinite=True)
    assert np.isinf(read_exr(tmp_path / "depth.exr")[0]["Z"][0, 1])
    with pytest.raises(SolasError, match="1 values are NaN"):
        write_exr(tmp_path / "depth.exr", {"Z": np.array([[np.nan]], dtype=np.float32)}, infinite=True)


def test_lines_under_an_hdrfilm_are_refused_with_the_way_out(mi):
    sensor = {"type": "lens_camera", "response": "lines", "film": {"type": "hdrfilm", "width": 8, "height": 6}}
    with pytest.raises(
        RuntimeError,
        match=r"response 'lines.*' has lines, which an hdrfilm cannot develop.*"
        r"specfilm.*continuous response \(srgb",
    ):
        mi.load_dict(sensor)
