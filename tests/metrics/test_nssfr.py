"""Natural-scene SFR on a synthetic scene whose blur grows from the centre to the periphery."""

import math

import imageio.v3 as iio
import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.metrics.annuli import ANNULI
from solas_mi.metrics.nssfr import find_edge_rois, natural_scene_sfr, plot_report
from solas_mi.metrics.targets import Square, slanted_squares


@pytest.fixture(scope="module")
def sharp(graded_scene):
    return graded_scene(texture=True)


@pytest.fixture(scope="module")
def degraded(graded_scene):
    return graded_scene((1.0, 1.4, 1.8), texture=True)


@pytest.fixture(scope="module")
def report(sharp):
    return natural_scene_sfr(sharp)


def test_mtf50_falls_from_centre_to_edge(report):
    centre, middle, edge = report.before
    assert min(s.count for s in report.before) >= 4
    assert centre.mean_mtf50 > middle.mean_mtf50 > edge.mean_mtf50
    assert centre.median_mtf50 > middle.median_mtf50 > edge.median_mtf50
    for s in report.before:
        assert s.sharpest10_mtf50 >= s.median_mtf50


def test_rois_lie_in_their_annulus_and_avoid_texture(report):
    bounds = (0.0, *ANNULI["automotive"])
    for m in report.rois:
        assert bounds[m.annulus] <= m.radius < bounds[m.annulus + 1] + 1e-12
        x, y, w, h = m.roi
        assert x + w <= 420 or x >= 480 or y + h <= 200 or y >= 260, f"ROI {m.roi} overlaps the texture"


def test_compare_measures_identical_rois(report, sharp, degraded):
    both = natural_scene_sfr(sharp, compare=degraded)
    assert [m.roi for m in both.rois] == [m.roi for m in report.rois]
    for m, alone in zip(both.rois, report.rois):
        assert m.before.mtf50 == alone.before.mtf50
    change = both.mean_change()
    assert change[0] == pytest.approx(0.0, abs=1e-12)  # the centre square is blurred the same in both
    assert change[1] < 0 and change[2] < 0
    ratio = [a.mean_mtf50 / b.mean_mtf50 for a, b in zip(both.after, both.before)]
    assert ratio[2] < ratio[1] < ratio[0]


def test_compare_with_itself_changes_nothing(sharp):
    same = natural_scene_sfr(sharp, compare=sharp.copy())
    changes = [c for c in same.mean_change() if c is not None]
    assert changes, "no annulus was measured: the comparison would pass vacuously"
    assert all(c == 0.0 for c in changes)


def test_equal_area_annuli(sharp):
    rep = natural_scene_sfr(sharp, annuli="equal-area")
    assert [s.r_outer for s in rep.before] == pytest.approx([math.sqrt(1 / 3), math.sqrt(2 / 3), 1.0])
    bounds = (0.0, *ANNULI["equal-area"])
    for m in rep.rois:
        assert bounds[m.annulus] <= m.radius < bounds[m.annulus + 1] + 1e-12


def test_square_gives_four_isolated_rois_and_close_edges_none():
    img = slanted_squares((200, 200), [Square(99.5, 99.5, 90, 5, 1.0, 0.2)], background=0.7)
    rois = find_edge_rois(img)
    assert len(rois) == 4
    bars = slanted_squares((200, 200), [Square(99.5, 99.5, 8, 5, 1.0, 0.2)], background=0.7)
    assert find_edge_rois(bars) == []  # the square's sides lie within 10 px of each other


def test_user_errors(sharp):
    with pytest.raises(SolasError, match="same size"):
        natural_scene_sfr(sharp, compare=sharp[:100])
    with pytest.raises(SolasError, match="annuli"):
        natural_scene_sfr(sharp, annuli="rings")


def test_plot_is_written(tmp_path, sharp, degraded):
    rep = natural_scene_sfr(sharp, compare=degraded)
    out = tmp_path / "fig5.png"
    plot_report(rep, sharp, out)
    img = iio.imread(out)
    assert img.shape[:2] == (520, 1300)
    assert [p.name for p in tmp_path.iterdir()] == ["fig5.png"]


def test_plot_axes_are_labelled_with_units(tmp_path, sharp, degraded, monkeypatch):
    """Figure 5's axes, read from the figure as it is saved: the image in pixels, the SFR against
    frequency in cycles per pixel."""
    from matplotlib.figure import Figure

    saved = []
    save = Figure.savefig
    monkeypatch.setattr(Figure, "savefig", lambda fig, *a, **k: (saved.append(fig), save(fig, *a, **k))[1])
    plot_report(natural_scene_sfr(sharp, compare=degraded), sharp, tmp_path / "fig5.png")
    image, sfr = saved[0].axes
    assert (image.get_xlabel(), image.get_ylabel()) == ("x (px)", "y (px)")
    assert sfr.get_xlabel() == "frequency (cy/px)" and sfr.get_ylabel().startswith("mean SFR (modulation")
    assert all(ax.get_title() for ax in (image, sfr))


@pytest.mark.parametrize(
    "image, message",
    [
        (np.array([]), "too small"),
        (np.zeros((0, 0)), "too small"),
        (np.zeros((1, 1)), "too small"),
        (np.full((64, 64), np.nan), "NaN or infinite"),
        (np.full((64, 64), np.inf), "NaN or infinite"),
        ([[0.5] * 64] * 3, "too small"),
        ("photo.png", "pass linear floats"),
        (None, "pass linear floats"),
        (np.zeros((64, 64), np.uint8), "pass linear floats"),
        (np.zeros((64, 64, 2)), "H×W×1, H×W×3 or H×W×4"),
    ],
)
def test_odd_images_are_refused_by_name(image, message):
    """Not an image of linear values an edge could be measured in: a SolasError saying so, never a
    TypeError or IndexError, nor a report of no ROIs as if the image had been measured."""
    with pytest.raises(SolasError, match=message):
        natural_scene_sfr(image)
    if image is not None:  # None: no comparison
        with pytest.raises(SolasError, match="comparison image"):
            natural_scene_sfr(np.zeros((64, 64)), compare=image)
