"""Degraded vs rendered flare (`validation.flare_routes`): a pinhole frame of a sun and two headlights degraded with
the coated double Gauss's ghosts (`degrade --ghosts`) against the lens camera's render of the scene with its ghosts
(`render --lens --ghosts`), at a small size."""

import pytest

from solas_mi import Lens
from solas_mi.cli import main
from solas_mi.optics.typical_ar import with_typical_ar
from solas_mi.validation.flare_routes import compare


@pytest.mark.slow
def test_degraded_ghosts_land_where_the_lens_camera_renders_them(tmp_path):
    """The strongest ghosts of the sun and of the headlights, each alone in both routes: centroids within 2 px,
    light (over each route's direct light of the sources) within 10 %; the flare label's hit masks overlap with
    IoU >= 0.8 (issue 39's acceptance)."""

    def run(*args):
        assert main([str(a) for a in args]) == 0, args

    found = compare(with_typical_ar(Lens.load("double-gauss-50mm")), tmp_path, run, size=(96, 72), spp=64,
                    path_spp=64, paths=2)  # fmt: skip
    assert {row["sources"] for row in found.paths} == {"sun", "headlights"}
    for row in found.paths:
        assert row["centroid_px"] < 2.0, row
        assert row["light_ratio"] == pytest.approx(1.0, abs=0.1), row
    assert found.iou >= 0.8, (found.iou, found.hit_pixels)
