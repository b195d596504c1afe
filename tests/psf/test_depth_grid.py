"""PSF grids over field and object distance (`psf.depth`, `GridSpec.distances_m`)."""

import math
from dataclasses import replace

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.psf.depth import DepthGrid, depth_grid, read_grid
from solas_mi.psf.grid import PSFGrid, psf_grid
from solas_mi.psf.spec import GridSpec, check_distances, inverse_spaced, parse_distances

SMALL = dict(grid=(3, 3), wavelengths_nm=[531.0], size=48, pitch_um=4.0, method="geometric", rays=64)


def test_inverse_spaced_nodes_are_even_in_one_over_distance():
    d = inverse_spaced(5, 2.0)
    assert math.isinf(d[0]) and d[-1] == pytest.approx(2.0)
    inv = [0.0 if math.isinf(v) else 1 / v for v in d]
    assert np.allclose(np.diff(inv), 0.5 / 4)
    assert parse_distances("5:2") == d
    assert parse_distances("inf,10,20") == (math.inf, 10.0, 20.0)
    assert check_distances((10.0, math.inf, 20.0)) == (math.inf, 20.0, 10.0)  # far to near


@pytest.mark.parametrize("bad", [(0.0,), (-1.0,), (float("nan"),), (5.0, 5.0), (), "10"])
def test_bad_distances_are_refused(bad):
    with pytest.raises(SolasError, match="distance"):
        GridSpec(distances_m=bad)


def test_a_grid_without_distances_keeps_its_key(doublet):
    assert "distances_m" not in GridSpec().canonical()
    assert GridSpec(distances_m=(math.inf, 10.0)).key("h") != GridSpec().key("h")
    with pytest.raises(SolasError, match="depth_grid"):
        psf_grid(doublet, GridSpec(distances_m=(10.0,)))


def test_nodes_are_the_lens_at_each_distance_with_its_image_plane(doublet, tmp_path):
    spec = GridSpec(**SMALL, distances_m=(math.inf, 20.0, 10.0))
    g = depth_grid(doublet, spec)
    assert g.distances_m == (math.inf, 20.0, 10.0) and np.allclose(g.inverse, [0, 0.05, 0.1])
    at_inf = psf_grid(doublet, replace(spec, distances_m=None))
    assert np.array_equal(g.layers[0].data, at_inf.data)
    near = replace(doublet, object_distance=10e3)  # same surfaces: same image plane
    assert near.surfaces[-1].thickness == doublet.surfaces[-1].thickness
    assert np.array_equal(g.layers[2].data, psf_grid(near, replace(spec, distances_m=None)).data)
    # focused at infinity, a nearer object is more defocused: wider PSFs, growing with 1/distance
    _y, x = np.mgrid[:48, :48]
    width = [float(np.sqrt(((x - 24) ** 2 * L.data[0, 1, 1]).sum() / L.data[0, 1, 1].sum())) for L in g.layers]
    assert width[0] < width[1] < width[2]
    # one camera for every node
    assert len({L.meta["pinhole_focal_mm"] for L in g.layers}) == 1
    path = str(tmp_path / "g.exr")
    g.write(path)
    back = read_grid(path)
    assert isinstance(back, DepthGrid) and back.distances_m == g.distances_m
    assert all(
        np.array_equal(a.data, b.data) and np.array_equal(a.chief_ray_mm, b.chief_ray_mm)
        for a, b in zip(g.layers, back.layers)
    )
    with pytest.raises(SolasError, match="object distance"):
        PSFGrid.read(path)
    at_inf.write(str(tmp_path / "one.exr"))
    assert isinstance(read_grid(str(tmp_path / "one.exr")), PSFGrid)


def test_subset_camera_and_viewpoint(doublet):
    from solas_mi.optics.paraxial import paraxial

    spec = GridSpec(**SMALL, distances_m=(math.inf, 20.0, 10.0))
    plain = depth_grid(doublet, spec)
    g = depth_grid(doublet, spec, camera_focal_mm=123.0, viewpoint_mm=0.0)
    assert all(L.meta["pinhole_focal_mm"] == 123.0 for L in g.layers)
    assert np.array_equal(g.layers[0].fields_deg, plain.layers[0].fields_deg)  # infinity: no parallax
    ep = paraxial(doublet).entrance_pupil_z_mm
    factor = (10e3 + ep) / 10e3  # seen from surface 1 instead of the entrance pupil
    assert np.allclose(
        np.tan(np.radians(g.layers[2].fields_deg)), np.tan(np.radians(plain.layers[2].fields_deg)) * factor
    )
    sub = plain.subset([0, 2])
    assert sub.distances_m == (math.inf, 10.0) and sub.layers[1] is plain.layers[2]
    with pytest.raises(SolasError, match="indices"):
        plain.subset([2, 0])
