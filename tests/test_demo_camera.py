"""`make demo`'s camera step at a small size: the street scene through the doublet with its labels, a
sensor preset and the default processor (`solas-mi camera` on a spectral render, whose few-spp RGB
holds negative values), and the sheet beside the depth and instance layers."""

import imageio.v3 as iio
import numpy as np

from solas_mi import demo
from solas_mi.imageio import read_exr, read_image


def test_camera_step(tmp_path, monkeypatch):
    monkeypatch.setattr(demo, "STREET_SET", ("width=48", "height=36", "fov=8", "target=0, 2, 140"))
    monkeypatch.setattr(demo, "STREET_SPP", 2)
    files = demo.camera_frame(tmp_path)
    assert set(files) == {"camera", "camera sheet"}
    render, render_meta = read_exr(tmp_path / "camera" / "street_render.exr")
    assert {"depth.Z", "instance.id", "normal.X"} <= set(render)
    raw, meta = read_exr(tmp_path / "camera" / "street_raw.exr")
    assert raw["RAW"].shape == (36, 48) and meta["sensor_model"] == demo.STREET_SENSOR
    least = min(float(render[c].min()) for c in "RGB")
    assert meta["negative_values_taken_as_zero"]["least"] == np.float32(min(least, 0.0))
    assert iio.imread(tmp_path / "camera" / "street_raw.png").shape == (36, 48, 3)
    sheet = iio.imread(tmp_path / "camera" / "camera_sheet.png")
    assert sheet.shape[1] > 3 * sheet.shape[0]  # one row of four panels
    # the street names its objects: the render boxes those it sees, and the sheet draws every box
    boxes = render_meta["labels"]["boxes"]
    assert boxes and all(name.split("_")[0] in {"car", "pedestrian", "pole", "post"} for name in boxes)
    frame = read_image(tmp_path / "camera" / "street_raw.png", linearize=False)
    assert demo.camera_sheet(render, render_meta["labels"], frame, tmp_path / "again.png", "t") == len(boxes)
