"""PSF grids: layout, file round trip, agreement with single PSFs, symmetry reuse, bad arguments."""

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.options import parse_wxh
from solas_mi.psf import psf, psf_grid
from solas_mi.psf.grid import PSFGrid, field_nodes


def test_grid_layout_and_round_trip(doublet, tmp_path):
    g = psf_grid(doublet, grid=(2, 3), wavelengths_nm=[486.0, 656.0], size=48, pupil_samples=32)
    assert g.data.shape == (2, 2, 3, 48, 48)
    assert g.fields_deg[0, 0].tolist() == pytest.approx([-4 / 3, 1.0])  # row 0 = top = +y field
    assert g.chief_ray_mm[0, 0, 0, 1] > 0 and g.chief_ray_mm[0, 0, 0, 0] < 0
    assert g.data.sum(axis=(-2, -1)) == pytest.approx(1.0, rel=1e-5)
    path = tmp_path / "grid.exr"
    g.write(str(path))
    back = PSFGrid.read(str(path))
    assert np.array_equal(back.data, g.data)
    assert back.wavelengths_nm == (486.0, 656.0) and back.pitch_um == 0.5
    assert np.allclose(back.chief_ray_mm, g.chief_ray_mm) and np.allclose(back.fields_deg, g.fields_deg)
    assert back.meta["lens_hash"] == doublet.hash and back.meta["method"] == "fraunhofer"
    assert back.meta["vignetted_by_surfaces"] == [] and len(back.meta["transmission"][0]) == 2
    assert [p.name for p in tmp_path.iterdir()] == ["grid.exr"]  # nothing half-written left


def test_grid_matches_single_psfs(doublet):
    g = psf_grid(
        doublet, grid=(1, 2), wavelengths_nm=[531.0], field_range_deg=(2.0, 0.0), size=40, field_sampling="edges"
    )
    one = psf(doublet, (2.0, 0.0), 531.0, size=40).data
    assert np.abs(g.data[0, 0, 1] - one).max() < 1e-6 * one.max()


def test_field_nodes():
    assert field_nodes(8, 2.0, "centers").tolist() == pytest.approx([-1.75 + 0.5 * i for i in range(8)])
    assert field_nodes(3, 2.0, "edges").tolist() == [-2.0, 0.0, 2.0]
    with pytest.raises(SolasError, match="grid 'eight' must look like 32x24"):
        parse_wxh("eight", "grid")
    assert parse_wxh("32x24", "grid") == (24, 32)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(grid=(0, 1)), r"grid \(0, 1\) must be \(rows, columns\), each an integer >= 1"),
        (dict(field_range_deg=(1.0, 2.0, 3.0)), r"field \(1.0, 2.0, 3.0\) must be two angles"),
        (dict(field_range_deg=(-1.0, 2.0)), r"field range \(-1, 2\) deg must be non-negative"),
        (dict(normalization="max"), "normalization 'max' must be one of"),
    ],
)
def test_bad_grid_arguments(doublet, kwargs, match):
    with pytest.raises(SolasError, match=match):
        psf_grid(doublet, **kwargs)


@pytest.mark.parametrize("method", ["fraunhofer", "geometric"])
def test_grid_symmetry_reuse_is_exact(doublet, method):
    """Nodes filled by mirroring/transposing a computed PSF equal a direct computation."""
    g = psf_grid(
        doublet,
        grid=(2, 3),
        wavelengths_nm=[531.0],
        field_range_deg=(2.0, 2.0),
        size=40,
        field_sampling="edges",
        method=method,
        rays=200,
        pupil_samples=48,
        normalization="none",
    )
    ny, nx = g.shape
    for r in range(ny):
        for c in range(nx):
            fx, fy = g.fields_deg[r, c]
            one = psf(
                doublet, (fx, fy), 531.0, size=40, method=method, rays=200, pupil_samples=48, normalization="none"
            )
            assert np.abs(g.data[0, r, c] - one.data).max() <= 1e-5 * one.data.max()
            assert g.chief_ray_mm[0, r, c] == pytest.approx(one.chief_ray_mm, abs=1e-12)


def test_the_preview_mosaic_is_bounded(doublet, tmp_path, monkeypatch):
    """The PNG is for looking: PSFs are block-averaged until the mosaic fits MOSAIC_PX, each tile still
    scaled to its own peak."""
    from solas_mi.psf import grid_file as grid_module

    g = psf_grid(doublet, grid=(2, 3), wavelengths_nm=[486.0, 531.0, 656.0], size=48, pupil_samples=32)
    assert g.preview().shape == (96, 144, 3)
    monkeypatch.setattr(grid_module, "MOSAIC_PX", 64)
    small = g.preview()
    assert small.shape == (2 * 16, 3 * 16, 3)  # 48 px PSFs averaged by 3 to fit 3 across 64 px
    assert small.reshape(2, 16, 3, 16, 3).max(axis=(1, 3)).min() == 1.0  # every tile keeps its peak
    g.write_png(tmp_path / "small.png")
    assert (tmp_path / "small.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_preview_png_has_labelled_axes_in_field_degrees(doublet, tmp_path, monkeypatch):
    """The mosaic's axes name what they show with units (field degrees at the node centres), and the
    title the tiles' physical width; read from the figure as it is saved."""
    from matplotlib.figure import Figure

    saved = []
    save = Figure.savefig
    monkeypatch.setattr(Figure, "savefig", lambda fig, *a, **k: (saved.append(fig), save(fig, *a, **k))[1])
    g = psf_grid(doublet, grid=(3, 4), wavelengths_nm=[531.0], size=32, pitch_um=2.0, pupil_samples=32)
    g.write_png(tmp_path / "grid.png")
    (ax,) = saved[0].axes
    assert ax.get_xlabel().startswith("field x (deg)") and ax.get_ylabel() == "field y (deg)"
    xs = [float(t.get_text()) for t in ax.get_xticklabels()]
    ys = [float(t.get_text()) for t in ax.get_yticklabels()]
    assert xs == pytest.approx(g.fields_deg[1, :, 0], abs=5e-3) and ys == pytest.approx(g.fields_deg[:, 2, 1], abs=5e-3)
    assert "32 px × 2 µm = 64 µm" in ax.get_title()
    assert (tmp_path / "grid.png").is_file()


@pytest.mark.parametrize("nodes, tile", [(32, 20), (2, 16)])
def test_every_label_of_the_mosaic_lies_inside_the_png(tmp_path, monkeypatch, nodes, tile):
    """The tick labels (node fields such as -0.0625), the axis labels and the title of a large grid's
    mosaic and of a tiny one lie wholly inside the saved PNG: none cut off at an edge."""
    from types import SimpleNamespace

    import imageio.v3 as iio
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from solas_mi.psf.preview import plot_grid

    saved = []
    save = Figure.savefig
    monkeypatch.setattr(Figure, "savefig", lambda fig, *a, **k: (saved.append(fig), save(fig, *a, **k))[1])
    centres = (np.arange(nodes) + 0.5) * 4.0 / nodes - 2.0  # `centers` sampling of ±2 deg
    fields = np.stack(np.meshgrid(centres, centres[::-1]), axis=-1)
    grid = SimpleNamespace(
        shape=(nodes, nodes), fields_deg=fields, size=160, pitch_um=0.5, wavelengths_nm=(656.0, 531.0, 486.0)
    )
    plot_grid(grid, np.zeros((nodes * tile, nodes * tile, 3)), tmp_path / "mosaic.png")
    (fig,) = saved
    (ax,) = fig.axes
    renderer = FigureCanvasAgg(fig).get_renderer()
    height, width = iio.imread(tmp_path / "mosaic.png").shape[:2]
    assert (width, height) == (round(fig.bbox.width), round(fig.bbox.height))
    texts = [ax.title, ax.xaxis.label, ax.yaxis.label, *ax.get_xticklabels(), *ax.get_yticklabels()]
    assert "-0.0625" in [t.get_text() for t in texts] or nodes == 2
    for text in texts:
        box = text.get_window_extent(renderer)
        assert box.x0 >= 0 and box.y0 >= 0 and box.x1 <= width and box.y1 <= height, text.get_text()
