"""Ghost grids (`psf.ghost_nodes`): a node is `ghosts` at its field, a field at another azimuth is the meridian's
turned, the cache reads back what it kept, and bad options are refused by name."""

import math

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.errors import SolasError
from solas_mi.psf import ghosts
from solas_mi.psf.ghost_grid_file import GhostGrid
from solas_mi.psf.ghost_nodes import CACHE, ghost_grid, ghost_kernel

WL = [587.6]
SMALL = {"radii": 3, "rays": 48, "kernel": 31, "wavelengths_nm": WL, "cache": False}


@pytest.fixture(scope="module")
def triplet():
    return Lens.load("cooke-triplet")


@pytest.fixture(scope="module")
def grid(triplet):
    return ghost_grid(triplet, field_deg=12.0, **SMALL)


def _table(report):
    return np.array([g.energy for g in report.ghosts]), np.array([g.centroid_mm for g in report.ghosts])


def test_a_node_is_the_ghosts_of_its_field(triplet, grid):
    """Each node's energies and centroids are those `ghosts` gives at its field (the same rays); its kernels sum
    to 1 and its image on the sensor holds the ghosts' energy."""
    for r, field in enumerate(grid.meta["fields_deg"][0]):
        energy, centroid = _table(ghosts(triplet, tuple(field), WL, rays=SMALL["rays"]))
        node = grid.node(0, r)
        lit = energy > 0
        np.testing.assert_allclose(node.energy[0], energy, rtol=1e-12, atol=0)
        np.testing.assert_allclose(node.centroid_mm[0][lit], centroid[lit], rtol=0, atol=1e-12)
        np.testing.assert_allclose(node.kernels[0][lit].sum(axis=(1, 2)), 1.0, rtol=1e-5)
    reach_um = (np.abs(node.centroid_mm).max() * 1e3 + node.pitch_um.max() * SMALL["kernel"]) * 1.01
    image = node.image(2.0 * reach_um / 512, 512, (0.0, 0.0))  # holds every ghost's kernel
    assert image.sum() == pytest.approx(node.energy.sum(), rel=1e-5)


def test_a_turned_field_is_the_meridian_turned(triplet, grid):
    """A field on the x axis (the meridian's node turned by -90 deg; the square launch grid turns onto itself, so
    the direct computation traces the same rays turned): energies, centroids, pitches and kernels as `ghosts`
    there; at 30 deg off the meridian (other rays) the totals agree to the sampling."""
    theta = grid.polar_deg[-1]
    report = ghosts(triplet, (theta, 0.0), WL, rays=SMALL["rays"])
    energy, centroid = _table(report)
    turned = grid.at((theta, 0.0))
    lit = energy > 0
    np.testing.assert_allclose(turned.energy[0], energy, rtol=1e-9, atol=0)
    np.testing.assert_allclose(turned.centroid_mm[0][lit], centroid[lit], rtol=0, atol=1e-9)
    for p, path in enumerate(report.hits):
        if energy[p] > 0:
            pitch, kernel = ghost_kernel(report.hits[path], report.ghosts[p], SMALL["kernel"])
            assert turned.pitch_um[0, p] == pytest.approx(pitch, rel=1e-9)
            assert np.abs(turned.kernels[0, p] - kernel).max() < 1e-3 * kernel.max()
    phi = math.radians(30.0)
    field = tuple(float(f) for f in triplet.field_type.field_of(math.radians(theta), math.cos(phi), math.sin(phi)))
    energy, _ = _table(ghosts(triplet, field, WL, rays=SMALL["rays"]))
    assert grid.at(field).energy.sum() == pytest.approx(energy.sum(), rel=0.03)


def test_the_cache_reads_back_what_it_kept(triplet, tmp_path, monkeypatch):
    monkeypatch.setenv("SOLAS_MI_CACHE_DIR", str(tmp_path))
    options = {**SMALL, "cache": True, "radii": 2}
    first = ghost_grid(triplet, **options)
    assert list((tmp_path / "ghost-grids").glob("*.exr"))
    monkeypatch.setattr("solas_mi.psf.ghost_nodes.compute", lambda *a: pytest.fail("computed again"))
    second = ghost_grid(triplet, **options)
    for key in ("polar_deg", "energy", "centroid_mm", "pitch_um", "kernels", "direct_mm"):
        assert np.array_equal(getattr(first, key), getattr(second, key)), key
    path = next((tmp_path / "ghost-grids").glob("*.exr"))
    path.write_bytes(path.read_bytes()[:-10])  # truncated: computed again
    monkeypatch.undo()
    monkeypatch.setenv("SOLAS_MI_CACHE_DIR", str(tmp_path))
    assert np.array_equal(ghost_grid(triplet, **options).kernels, first.kernels)
    assert CACHE.check(path, {"lens_hash": triplet.hash, "ghost_grid": first.meta["options"]}) is None


def test_the_file_round_trips(grid, tmp_path):
    grid.write(tmp_path / "g.exr", tmp_path / "g.json")
    back = GhostGrid.read(tmp_path / "g.exr")
    assert np.array_equal(back.kernels, grid.kernels) and np.array_equal(back.energy, grid.energy)
    assert (tmp_path / "g.json").read_text().count('"paths"') == 1


@pytest.mark.parametrize(
    "option,value",
    [("radii", 1), ("radii", 2.5), ("kernel", 4), ("kernel", 32), ("field_deg", 95.0), ("field_deg", 0), ("rays", 2),
     ("azimuths", 3), ("wavelengths_nm", [587.6, 587.6])],
)  # fmt: skip
def test_bad_options_are_refused_by_name(triplet, option, value):
    with pytest.raises(SolasError, match=option):
        ghost_grid(triplet, **{**SMALL, option: value})


def test_a_field_beyond_the_grid_is_refused(grid):
    with pytest.raises(SolasError, match="beyond the ghost grid"):
        grid.at((0.0, 13.0))


def test_the_command_writes_the_grid_and_its_json(tmp_path, monkeypatch, capsys):
    from solas_mi.cli import build_parser, main
    from solas_mi.psf.ghost_grid_file import DEFAULT_IRIS_AZIMUTHS, DEFAULT_KERNEL, DEFAULT_RADII

    helps = build_parser()._subparsers._group_actions[0].choices["ghost-grid"].format_help()
    assert f"default {DEFAULT_IRIS_AZIMUTHS};" in helps

    monkeypatch.setenv("SOLAS_MI_CACHE_DIR", str(tmp_path / "cache"))
    out = tmp_path / "g.exr"
    assert main(["ghost-grid", "solas-doublet", "--radii", "2", "--rays", "16", "--kernel", "15", "-o", str(out)]) == 0
    back = GhostGrid.read(out)
    assert back.energy.shape == (3, 1, 2, 3) and (tmp_path / "g.json").is_file()
    assert main(["ghost-grid", "solas-doublet", "--radii", "0", "-o", str(out)]) == 2
    assert "radii 0 must be an integer from 2" in capsys.readouterr().err
    monkeypatch.setattr("solas_mi.budget.available_memory", lambda: 1 << 20)  # 1 MiB free: refused before the work
    assert main(["ghost-grid", "solas-doublet", "-o", str(tmp_path / "big.exr")]) == 2
    kernels = 3 * DEFAULT_RADII * 3  # the doublet's wavelengths, the radii, its three paths
    assert (
        f"ghost-grid of {kernels} kernels of {DEFAULT_KERNEL}x{DEFAULT_KERNEL} needs about" in capsys.readouterr().err
    )


def test_an_iris_grid_turns_by_whole_sectors(triplet):
    """A four-blade iris repeats every 90 deg: a field at azimuth 180 deg is the 90 deg node turned by one sector
    (exact: the launch grid turns onto itself), and one between two azimuth nodes lies between them."""
    import tomllib

    from solas_mi.resources import resource_dir

    with open(resource_dir("scenes") / "lenses" / "cooke_triplet.toml", "rb") as f:
        spec = tomllib.load(f)
    spec["surface"][triplet.stop_index].update(blades=4, blade_rotation=10.0)
    iris = Lens.from_dict(spec)
    grid = ghost_grid(iris, field_deg=12.0, azimuths=2, **{**SMALL, "radii": 2})
    assert grid.sector_deg == 90.0 and grid.azimuth_deg.tolist() == [90.0, 135.0]
    energy, centroid = _table(ghosts(iris, (-12.0, 0.0), WL, rays=SMALL["rays"]))
    turned = grid.at((-12.0, 0.0))
    np.testing.assert_allclose(turned.energy[0], energy, rtol=1e-9, atol=0)
    lit = energy > 0
    np.testing.assert_allclose(turned.centroid_mm[0][lit], centroid[lit], rtol=0, atol=1e-9)


def test_a_field_between_nodes_is_near_its_direct_ghosts(triplet):
    """Midway between two radii, 37 deg off the meridian: the interpolated ghosts against `ghosts` there (the
    brighter ghosts' centroids within a tenth of their RMS radius, their total within 2 %)."""
    grid = ghost_grid(triplet, field_deg=20.0, **{**SMALL, "radii": 9, "rays": 64})
    theta, phi = math.radians(13.75), math.radians(37.0)
    field = tuple(float(f) for f in triplet.field_type.field_of(theta, math.cos(phi), math.sin(phi)))
    report = ghosts(triplet, field, WL, rays=64)
    energy, centroid = _table(report)
    rms = np.array([g.rms_mm for g in report.ghosts])
    at = grid.at(field)
    bright = energy > 0.05 * energy.max()
    assert at.energy.sum() == pytest.approx(energy.sum(), rel=0.02)
    assert (np.hypot(*(at.centroid_mm[0][bright] - centroid[bright]).T) < 0.1 * rms[bright]).all()


@pytest.mark.parametrize("ratio", [0.23, 1.0, 3.7])  # the grid's pitch over the kernel's: finer, equal, coarser
def test_a_ghosts_image_keeps_its_light_and_its_centroid(grid, ratio):
    """Each ghost resampled onto the sensor grid by area: all its light (within the grid) and its centroid, to half
    a pixel of the grid, at its kernel's centroid."""
    from solas_mi.psf.ghost_grid_file import NodeGhosts

    node = grid.node(0, 2)
    k = node.kernels.shape[-1]
    offsets = np.arange(k) - k // 2
    for p in np.argsort(-node.energy[0])[:3]:
        alone = np.zeros_like(node.energy)
        alone[0, p] = node.energy[0, p]
        one = NodeGhosts(alone, node.centroid_mm, node.pitch_um, node.kernels, node.direct_mm)
        kernel, pitch = node.kernels[0, p], node.pitch_um[0, p]
        pitch_um = ratio * pitch
        centre = node.centroid_mm[0, p] + 1e-3 * pitch * np.array([(kernel.sum(0) * offsets).sum(),
                                                                    -(kernel.sum(1) * offsets).sum()])  # fmt: skip
        size = int(2 * (pitch * k / pitch_um + 4)) | 1
        image = one.image(pitch_um, size, centre_mm=node.centroid_mm[0, p])[0]
        assert image.sum() == pytest.approx(node.energy[0, p], rel=1e-6)
        rows, cols = np.indices(image.shape) - size // 2
        got = (
            node.centroid_mm[0, p]
            + 1e-3 * pitch_um * np.array([(image * cols).sum(), -(image * rows).sum()]) / image.sum()
        )
        assert np.hypot(*(got - centre)) < 0.5e-3 * pitch_um


def test_the_command_refuses_a_field_list_it_would_cut_to_its_first_value(tmp_path, capsys):
    """--field-deg of ghost-grid is one polar angle: "1,2" once ran on 1 deg (the 2 dropped silently); it is
    refused, naming the value, before any work (exit 2, nothing written)."""
    from solas_mi.cli import main

    out = tmp_path / "g.exr"
    with pytest.raises(SystemExit) as refused:
        main(["ghost-grid", "solas-doublet", "--field-deg", "1,2", "--radii", "2", "-o", str(out)])
    assert refused.value.code == 2
    assert "'1,2'" in capsys.readouterr().err and not out.exists()
