"""PSF grids laid out on the sensor (`--layout sensor`): nodes at sensor positions, each PSF's chief
ray on its node, mirror symmetry, and the convolution placing each node's PSF at its node."""

import numpy as np
import pytest

from solas_mi import Lens, SolasError
from solas_mi.convolution.methods import degrade
from solas_mi.psf.grid import PSFGrid, psf_grid

LINE_D = 587.5618


@pytest.fixture(scope="module")
def fisheye_grid():
    return psf_grid(
        Lens.load("nikkor-fisheye"),
        grid=(5, 5),
        wavelengths_nm=[LINE_D],
        size=32,
        pitch_um=4.0,
        pupil_samples=128,
        layout="sensor",
        sensor_mm=(19.0, 19.0),
    )


def test_chief_rays_land_on_the_nodes(fisheye_grid, doublet):
    g = fisheye_grid
    nodes = np.array(g.meta["node_mm"])
    assert g.meta["layout"] == "sensor" and nodes.shape == (5, 5, 2)
    assert np.allclose(nodes[0, 0], [-7.6, 7.6]) and np.allclose(nodes[2, 2], [0.0, 0.0])
    # the inverted height table puts every chief ray within 0.1 µm of its node (≪ the 4 µm PSF pitch)
    assert np.abs(g.chief_ray_mm[0] - nodes).max() < 1e-4
    # corners at 10.7 mm from the axis are at polar angles beyond 60°: fields a tangent grid cannot reach evenly
    assert np.hypot(*g.fields_deg[0, 0]) > 60.0
    # mirror symmetry of a centred lens: mirrored nodes get exactly mirrored fields and equal transmission
    f, tr = g.fields_deg, np.array(g.meta["transmission"])[0]
    assert np.array_equal(f[0, 4], f[0, 0] * np.array([-1, 1])) and np.array_equal(f[4, 0], f[0, 0] * np.array([1, -1]))
    assert tr[0, 0] == tr[0, 4] == tr[4, 0] == tr[4, 4] and 0 < tr[0, 0] < tr[2, 2]
    # a lens of tangent fields takes the same layout: its chief rays land on its nodes too
    t = psf_grid(
        doublet,
        grid=(3, 3),
        wavelengths_nm=[531.0],
        size=16,
        pitch_um=2.0,
        pupil_samples=32,
        layout="sensor",
        sensor_mm=(6.0, 4.0),
    )
    assert np.abs(t.chief_ray_mm[0] - np.array(t.meta["node_mm"])).max() < 1e-4


def test_round_trip_through_exr(fisheye_grid, tmp_path):
    path = tmp_path / "grid.exr"
    fisheye_grid.write(str(path))
    back = PSFGrid.read(str(path))
    assert back.meta["layout"] == "sensor" and back.meta["node_mm"] == fisheye_grid.meta["node_mm"]
    assert np.array_equal(back.data, fisheye_grid.data)


def test_degrade_puts_a_node_psf_at_its_node(fisheye_grid):
    """A point at a node's pixel comes out as that node's PSF: same energy, centroid at the node plus
    the chief ray's offset plus the PSF's own centroid (0.2 mm pixels: 95 px span the 19 mm sensor)."""
    g, width = fisheye_grid, 95
    image = np.zeros((width, width))
    image[9, 9] = 1.0  # node (row 0, column 0) at (-7.6, 7.6) mm: pixel (9, 9)
    out = degrade(image, g, dtype=np.float64)
    rows, cols = np.indices(out.shape)
    assert abs(out.sum() - 1.0) < 1e-6
    p = g.data[0, 0, 0].astype(np.float64)
    x_um = (np.arange(p.shape[0]) - p.shape[0] // 2) * g.pitch_um
    cx, cy = (p.sum(0) * x_um).sum() / p.sum(), -(p.sum(1) * x_um).sum() / p.sum()
    off = (g.chief_ray_mm[0, 0, 0] - np.array(g.meta["node_mm"])[0, 0]) / 0.2
    assert abs((out * cols).sum() - (9 + off[0] + cx / 200)) < 1e-6
    assert abs((out * rows).sum() - (9 - off[1] - cy / 200)) < 1e-6
    with pytest.raises(SolasError, match="sensor aspect"):
        degrade(np.ones((50, 95)), g)


def test_sensor_beyond_the_image_circle_is_an_error():
    with pytest.raises(SolasError, match="beyond the lens's image circle"):
        psf_grid(
            Lens.load("nikkor-fisheye"),
            grid=(3, 3),
            wavelengths_nm=[LINE_D],
            size=16,
            pupil_samples=32,
            layout="sensor",
            sensor_mm=(40.0, 40.0),
        )  # corner nodes 18.9 mm off axis; the image circle ends near 14.3 mm
