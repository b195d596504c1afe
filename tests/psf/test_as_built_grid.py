"""PSF grids of a lens as built (`psf.as_built_grid` through `psf.grid.psf_grid`): every node traced, none
mirrored; a lens placed with zero breaks gives the symmetric grid, a tilted sensor's +y and −y nodes differ and each
is `psf.as_built.geometric` at its field; `solas-mi psf-grid` writes a grid `PSFGrid.read` reads back."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.errors import SolasError
from solas_mi.optics.placement import Placement
from solas_mi.psf import as_built, psf_grid
from solas_mi.psf.as_built_methods import PATHS
from solas_mi.psf.grid_file import PSFGrid
from solas_mi.psf.registry import METHODS

PITCH_UM, SIZE, RAYS = 2.0, 33, 64  # an odd size: the window is not cut, so a node is its PSF normalised


def _zero_placed(lens: Lens) -> Lens:
    """`lens` with a coordinate break of all zeros before every surface and at the image plane."""
    return replace(
        lens, surfaces=tuple(replace(s, placement=Placement()) for s in lens.surfaces), image_placement=Placement()
    )


def _tilted() -> Lens:
    return replace(Lens.load("solas-doublet"), name="tilted-doublet", image_placement=Placement(tilt_x=0.5))


@pytest.mark.parametrize("name", ["solas-doublet", "cooke-triplet"])
def test_a_lens_placed_with_zero_breaks_gives_the_symmetric_grid(name):
    """Every node traced by the NumPy tracer against the Dr.Jit tracer's mirrored nodes: the same chief rays,
    nodes that are mirror images of each other without being mirrored (the symmetry checked, not assumed), and
    the same light to the ray sampling (the two paths size their entrance grids apart: the as-built one by a
    coarse pass, so not 1e-9; measured on the doublet: centroids 0.011 px apart at 64 rays, 0.0013 at 256)."""
    lens = Lens.load(name)
    options = {"grid": (3, 4), "method": "geometric", "rays": RAYS, "size": SIZE, "pitch_um": PITCH_UM}
    expected = psf_grid(lens, **options)
    grid = psf_grid(_zero_placed(lens), **options)
    assert np.abs(grid.chief_ray_mm - expected.chief_ray_mm).max() < 1e-9
    peak = grid.data.max(axis=(-2, -1), keepdims=True)
    assert (np.abs(grid.data - grid.data[:, :, ::-1, :, ::-1]) / peak).max() < 1e-9  # (x, y) against (−x, y)
    assert (np.abs(grid.data - grid.data[:, ::-1, :, ::-1, :]) / peak).max() < 1e-9  # (x, y) against (x, −y)
    pixel = np.arange(SIZE)
    for summed in (-1, -2):  # the y centroid, then the x one (pixels)
        centroid = [(g.data.sum(axis=summed) * pixel).sum(axis=-1) for g in (grid, expected)]
        assert np.abs(centroid[0] - centroid[1]).max() < 0.05
    assert "every node traced" in grid.meta["path"]
    assert "path" not in expected.meta


def test_a_tilted_sensors_grid_differs_between_plus_and_minus_y_and_each_node_is_its_fields_psf():
    lens = _tilted()
    grid = psf_grid(lens, grid=(2, 2), method="geometric", rays=RAYS, size=SIZE, pitch_um=PITCH_UM)
    assert grid.meta["path"].startswith(PATHS["geometric"])
    for k, w in enumerate(grid.wavelengths_nm):
        fields = grid.fields_deg.reshape(-1, 2)
        expected, image_xy, _ = as_built.geometric(lens, fields, w, PITCH_UM, SIZE, RAYS)
        expected = expected / expected.sum(axis=(1, 2), keepdims=True)
        data = grid.data[k].reshape(-1, SIZE, SIZE)
        assert np.abs(data - expected).max() < 1e-6 * expected.max()  # float32 storage
        assert np.abs(grid.chief_ray_mm[k].reshape(-1, 2) - image_xy).max() < 1e-9
        top, bottom = grid.data[k, 0], grid.data[k, 1]  # +y row, −y row (same x)
        assert np.abs(top.max(axis=(-2, -1)) - bottom.max(axis=(-2, -1))).min() > 0.02 * top.max()


def test_solas_mi_psf_grid_of_a_lens_as_built_writes_a_grid_and_refuses_what_it_does_not_take(tmp_path, capsys):
    from solas_mi.cli import main

    _tilted().save(tmp_path / "tilted.toml")
    args = ["psf-grid", str(tmp_path / "tilted.toml"), "--grid", "2x2", "--size", "24", "--pitch-um", f"{PITCH_UM}"]
    out = tmp_path / "grid.exr"
    wl = ["--wavelengths-nm", "486.1,587.6"]
    assert main([*args, *wl, "--psf-method", "fraunhofer", "--pupil-samples", "32", "-o", str(out)]) == 0
    grid = PSFGrid.read(str(out))  # the Fraunhofer path: one wavelength per window, both wavelengths in the grid
    assert grid.data.shape == (2, 2, 2, 24, 24) and np.isfinite(grid.data).all()
    assert grid.meta["path"].startswith(PATHS["fraunhofer"]) and "nominal axis" in grid.meta["paraxial_axis"]
    for method in [m for m in METHODS if m not in PATHS]:
        capsys.readouterr()
        assert main([*args, "--psf-method", method, "-o", str(tmp_path / "refused.exr")]) == 2
        assert f"PSF method {method!r} does not take it" in capsys.readouterr().err
    with pytest.raises(SolasError, match="takes layout 'field'"):
        psf_grid(_tilted(), grid=(1, 1), layout="sensor")
    assert not (tmp_path / "refused.exr").exists()
