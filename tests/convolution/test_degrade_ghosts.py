"""`degrade --ghosts` (`convolution.ghosts`): the lens's ghosts of a frame's bright sources added to the degraded
frame, each at its own place and shape from the ghost grid; held to the ghost grid's energies and centroids (by the
pinhole camera's own arithmetic), to the degraded frame without ghosts, and to its refusals."""

import dataclasses
import math

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.convolution.frame_fields import FrameFields
from solas_mi.convolution.ghosts import frame_ghosts
from solas_mi.convolution.kernels import channel_wavelengths
from solas_mi.convolution.spec import DegradeSpec
from solas_mi.imageio import read_exr, write_exr, write_png
from solas_mi.labelkinds import FLARE_LAYERS, MAX_RATIO, flare_layers
from solas_mi.optics.frame import FrameCamera
from solas_mi.psf import ghost_grid, psf_grid

W, H = 320, 240
SHRINK = 100.0  # the doublet's ghosts are wider than its 4 deg frame: their kernels shrunk to fit it (placement only)


@pytest.fixture(scope="module")
def doublet_grids(doublet):
    """The doublet's PSF grid over +-2 deg and its ghost grid over the grid's corner, at the grid's wavelengths."""
    grid = psf_grid(doublet, grid=(3, 3), size=32)
    polar = max(doublet.field_type.polar(f)[0] for f in np.asarray(grid.fields_deg).reshape(-1, 2))
    ghosts = ghost_grid(doublet, radii=3, rays=32, kernel=15, cache=False, field_deg=math.degrees(polar),
                        wavelengths_nm=list(grid.wavelengths_nm))  # fmt: skip
    return grid, ghosts


def compact(ghosts):
    """The ghost grid with every kernel's pitch shrunk (`SHRINK`): the same energies and centroids, each ghost inside
    the frame."""
    return dataclasses.replace(ghosts, pitch_um=ghosts.pitch_um / SHRINK)


def test_the_ghosts_added_hold_the_sources_light_times_the_ghost_energy(doublet, doublet_grids):
    """A bright disc of 3 colours: the ghosts on the frame hold Σ over its pixels of value x the ghost energy
    fraction at the pixel's own field (each pixel's ghosts looked up alone), within 1 %."""
    grid, ghosts = doublet_grids
    ghosts = compact(ghosts)
    fields = FrameFields(doublet, grid, W, H)
    image = np.full((H, W, 3), 0.5)
    rows, cols = np.mgrid[:H, :W]
    disc = np.hypot(cols - 210.0, rows - 70.0) <= 3.5
    image[disc] = (4000.0, 2500.0, 1000.0)
    channels = channel_wavelengths(grid, 3)
    flare, meta = frame_ghosts(image, ghosts, fields, channels, 10.0)
    expected = np.zeros(3)
    for r, c in zip(*np.nonzero(disc)):
        at = ghosts.at(tuple(fields.field_deg(np.array([float(c)]), np.array([float(r)]))[0]))
        expected += image[r, c] * np.array([at.energy[k].sum() for k in channels])
    assert meta["source_pixels"] == disc.sum() and meta["cells"] >= 1
    assert flare.sum(axis=(0, 1)) == pytest.approx(expected, rel=0.01)
    assert np.asarray(meta["ghost_light"]) == pytest.approx(expected, rel=0.01)


def test_the_ghosts_of_each_path_alone_add_up_to_all_of_them(doublet, doublet_grids):
    """`GhostGrid.only(k)`, the grid of one ghost path (what the degraded-vs-rendered comparison places ghost by
    ghost): the frames of each path alone sum to the frame of every path, each path's light its energy's share."""
    grid, ghosts = doublet_grids
    ghosts = compact(ghosts)
    fields = FrameFields(doublet, grid, W, H)
    image = np.full((H, W, 3), 0.5)
    image[66:69, 150:153] = 3000.0
    channels = channel_wavelengths(grid, 3)
    every = frame_ghosts(image, ghosts, fields, channels, 10.0)[0]
    alone = [frame_ghosts(image, ghosts.only(k), fields, channels, 10.0) for k in range(len(ghosts.paths))]
    assert [ghosts.only(k).paths for k in range(len(ghosts.paths))] == [[p] for p in ghosts.paths]
    assert np.allclose(sum(flare for flare, _ in alone), every, rtol=1e-9, atol=1e-12)
    assert sum(np.asarray(meta["ghost_light"]) for _, meta in alone) == pytest.approx(
        frame_ghosts(image, ghosts, fields, channels, 10.0)[1]["ghost_light"], rel=1e-9
    )


def test_a_bright_pixel_at_a_node_casts_each_ghost_at_the_grids_centroid(doublet, doublet_grids):
    """One bright pixel exactly at the ghost grid's node (0, theta_1): each ghost alone lands at its centroid in the
    grid, turned into pixels by the pinhole frame's camera (focal length over fx), within 1 px."""
    grid, ghosts = doublet_grids
    ghosts = compact(ghosts)
    theta = math.radians(ghosts.polar_deg[1])
    fx, cx, cy, up = 80.0 / math.tan(theta), 160.0, 120.0, 80  # the node 80 rows above the axis
    frame = FrameCamera("pinhole", intrinsics=(fx, fx, cx, cy))
    fields = FrameFields(doublet, grid, W, H, frame)
    assert fields.field_deg(np.array([cx]), np.array([cy - up]))[0] == pytest.approx(
        ghosts.meta["fields_deg"][0][1], abs=1e-9
    )
    image = np.zeros((H, W, 3))
    image[int(cy) - up, int(cx)] = 1e4
    pitch_mm = float(grid.meta["pinhole_focal_mm"]) / fx
    channels = channel_wavelengths(grid, 3)
    lit = [p for p in range(len(ghosts.paths)) if ghosts.energy[:, 0, 1, p].min() > 0]
    assert lit
    for p in lit:
        energy = np.zeros_like(ghosts.energy)
        energy[..., p] = ghosts.energy[..., p]
        flare, _ = frame_ghosts(image, dataclasses.replace(ghosts, energy=energy), fields, channels, 10.0)
        for c, k in enumerate(channels):
            x, y = ghosts.centroid_mm[k, 0, 1, p]
            plane = flare[..., c]
            rows, cols = np.mgrid[:H, :W]
            got = (plane * cols).sum() / plane.sum(), (plane * rows).sum() / plane.sum()
            assert got == pytest.approx((cx + x / pitch_mm, cy - y / pitch_mm), abs=1.0)


def test_the_flare_label_is_zero_without_stray_light_and_never_nan():
    """The ratio is 0 where no ghost arrives, the stray light over the direct where both are, capped where the
    direct image is black; never NaN or infinite."""
    flare = np.zeros((2, 3, 3))
    flare[0, 1] = 0.3
    flare[1, 2] = 0.6
    direct = np.ones((2, 3, 3))
    direct[1, 2] = 0.0
    layers = flare_layers(direct, flare)
    assert layers["flare.irradiance"][0, 1] == pytest.approx(0.3)
    assert layers["flare.ratio"][0, 1] == pytest.approx(0.3)
    assert layers["flare.ratio"][1, 2] == MAX_RATIO
    assert layers["flare.ratio"][0, 0] == 0 and layers["flare.irradiance"][0, 0] == 0
    assert all(np.isfinite(v).all() for v in layers.values())


@pytest.mark.parametrize(
    "options, named",
    [
        (dict(ghosts=True, ghost_threshold=-1.0), "ghost threshold -1.0"),
        (dict(ghosts=True, ghost_threshold=math.nan), "ghost threshold nan"),
        (dict(ghosts=True, ghost_threshold=0), "ghost threshold 0"),
        (dict(ghost_threshold=50.0), "ghost threshold 50.0 is for ghosts"),
        (dict(ghosts="yes"), "ghosts 'yes'"),
    ],
)
def test_bad_ghost_options_are_refused_by_name(options, named):
    with pytest.raises(SolasError, match=named):
        DegradeSpec(**options)


@pytest.fixture
def frames(tmp_path, doublet_grids):
    """The PSF grid's file, an HDR frame with a sun and the same frame as PNG."""
    grid, _ = doublet_grids
    grid.write(str(tmp_path / "grid.exr"))
    image = np.full((H, W, 3), 0.2, np.float32)
    image[58:63, 198:203] = 5000.0
    write_exr(tmp_path / "sun.exr", {"R": image[..., 0], "G": image[..., 1], "B": image[..., 2]}, {})
    write_png(tmp_path / "sun.png", np.minimum(image, 1.0))
    return tmp_path


def degrade_cli(folder, *args):
    from solas_mi.cli import main

    return main(["degrade", *map(str, args), "--psf-grid", str(folder / "grid.exr")])


def test_ghosts_off_is_the_degraded_frame_and_on_adds_the_flare_label(frames, capsys):
    """Without --ghosts the output is exactly `degrade`'s and no label file appears; with it the same frame plus the
    ghosts (as much light more as the metadata says landed in the frame), and the flare label beside it; the
    shipped doublet states no coatings, which it warns of."""
    from solas_mi.convolution.methods import degrade
    from solas_mi.imageio import read_image

    assert degrade_cli(frames, frames / "sun.exr", "-o", frames / "off.exr") == 0
    off, _ = read_exr(frames / "off.exr")
    plain = degrade(read_image(frames / "sun.exr"), str(frames / "grid.exr"))
    assert all(np.array_equal(off[name], plain[..., c]) for c, name in enumerate("RGB"))
    assert not (frames / "off.labels.exr").exists()
    capsys.readouterr()
    assert degrade_cli(frames, frames / "sun.exr", "--ghosts", "-o", frames / "on.exr") == 0
    assert "states no coatings" in capsys.readouterr().err
    on, meta = read_exr(frames / "on.exr")
    added = np.array([(on[n].astype(np.float64) - off[n]).sum() for n in "RGB"])
    starburst = meta["ghosts"]["starburst"]  # the wings move light, and carry some beyond the frame's edges
    moved = np.subtract(starburst["light_in_frame"], starburst["light_given"])
    assert added == pytest.approx(np.add(meta["ghosts"]["ghost_light_in_frame"], moved), rel=1e-3, abs=1e-2)
    assert meta["ghosts"]["source_pixels"] == 25
    layers, label_meta = read_exr(frames / "on.labels.exr")
    assert set(layers) == set(FLARE_LAYERS) and "flare" in label_meta["labels"]
    assert layers["flare.irradiance"].max() > 0 and np.isfinite(layers["flare.ratio"]).all()


def test_an_ldr_frame_is_refused_without_force_and_warned_of_with_it(frames, capsys):
    assert degrade_cli(frames, frames / "sun.png", "--ghosts", "-o", frames / "ldr.exr") == 2
    err = capsys.readouterr().err
    assert "sun.png" in err and "--force" in err and "clipped" in err
    assert not (frames / "ldr.exr").exists()
    assert degrade_cli(frames, frames / "sun.png", "--ghosts", "--force", "-o", frames / "ldr.exr") == 0
    assert "clipped" in capsys.readouterr().err


def test_a_batch_with_ghosts_resumes_to_the_same_frames(frames):
    """A batch of two HDR frames with ghosts, one output removed and the batch run again: that item done again to the
    same pixels and flare label, the other skipped; a batch without ghosts is another batch."""
    from solas_mi.batch import degrade_batch

    folder = frames / "in"
    folder.mkdir()
    for name in ("a", "b"):
        (folder / f"{name}.exr").write_bytes((frames / "sun.exr").read_bytes())
    spec = DegradeSpec(ghosts=True, ghost_threshold=100.0)
    kwargs = dict(psf_grid=frames / "grid.exr", workers=1, progress=False)
    first = degrade_batch([folder], frames / "out", spec, **kwargs)
    assert [j.status for j in first.jobs] == ["done", "done"]
    before = {p: read_exr(p)[0] for p in sorted((frames / "out").glob("b*.exr"))}
    (frames / "out" / "b.exr").unlink()
    again = degrade_batch([folder], frames / "out", spec, **kwargs)
    assert sorted(j.status for j in again.jobs) == ["done", "skipped"]
    for path, channels in before.items():
        after = read_exr(path)[0]
        assert all(np.array_equal(after[n], channels[n]) for n in channels)
    plain = degrade_batch([folder], frames / "out", DegradeSpec(), **kwargs)
    assert [j.status for j in plain.jobs] == ["done", "done"]


def test_a_fisheye_frames_sources_have_their_direct_image_on_their_own_pixel():
    """A Kannala-Brandt frame of the fisheye: a pixel's field (by its calibration), the ghost grid's direct image of
    that field, and that image point mapped back through the lens's chief rays and the calibration, land on the
    pixel (within 0.6 px; the grid's direct image is interpolated between its radii): the mapping the ghosts take."""
    from solas_mi import Lens

    lens = Lens.load("nikkor-fisheye")
    grid = psf_grid(lens, grid=(3, 3), size=32, method="geometric", rays=32, field_range_deg=(60.0, 45.0))
    f_px = 300 / math.radians(60)
    frame = FrameCamera("kannala-brandt", intrinsics=(f_px, f_px, 319.5, 239.5), coefficients=(0.0, 0.0, 0.0, 0.0))
    fields = FrameFields(lens, grid, 640, 480, frame)
    ghosts = ghost_grid(lens, radii=12, rays=64, kernel=15, cache=False, field_deg=70.0, wavelengths_nm=[531.0])
    for pixel in ((500.0, 100.0), (320.0, 240.0), (100.0, 400.0)):
        field = fields.field_deg(np.array([pixel[0]]), np.array([pixel[1]]))[0]
        assert fields.pixel(ghosts.at(tuple(field)).direct_mm[0])[0] == pytest.approx(pixel, abs=0.6)


def test_degraded_frames_carry_the_iris_starburst_as_renders_do(frames, doublet):
    """degrade --ghosts spreads the stop's diffraction wings from the degraded frame (as render --ghosts from the
    direct image): the kernel on the frame's own pixels (its pitch the grid camera's, 2 f tan(half field) / width)
    at the lens's working f-number, its centre pixel's share of a round stop's light that of the Airy pattern's
    encircled energy within the pixel's equal-area circle (1 - J0² - J1², within 3 %: a square is not a circle);
    away from the sun (ghost-free: the ghosts alone computed apart), the flare label holds the sun's wings."""
    from scipy.special import j0, j1

    from solas_mi.convolution.ghosts import FrameGhosts
    from solas_mi.imageio import read_image
    from solas_mi.psf.grid_file import PSFGrid
    from solas_mi.psf.stray_light import working_f_number

    assert degrade_cli(frames, frames / "sun.exr", "--ghosts", "-o", frames / "on.exr") == 0
    _, meta = read_exr(frames / "on.exr")
    starburst = meta["ghosts"]["starburst"]
    grid = PSFGrid.read(str(frames / "grid.exr"))
    focal, half = grid.meta["pinhole_focal_mm"], math.radians(grid.meta["field_range_deg"][0])
    assert starburst["pitch_um"] == pytest.approx(2e3 * focal * math.tan(half) / W, rel=1e-9)
    assert starburst["f_number"] == pytest.approx(working_f_number(doublet), rel=1e-9)
    x = (
        math.pi
        * starburst["pitch_um"]
        / math.sqrt(math.pi)
        / (starburst["wavelength_nm"] * 1e-3 * starburst["f_number"])
    )
    assert 1.0 - starburst["wings"] == pytest.approx(1.0 - j0(x) ** 2 - j1(x) ** 2, rel=0.03)
    assert starburst["wings"] > 0.01
    layers, _ = read_exr(frames / "on.labels.exr")
    planner = FrameGhosts.plan(frames / "sun.exr", grid, DegradeSpec(ghosts=True), force=False, lens=doublet)
    ghosts = frame_ghosts(read_image(frames / "sun.exr"), planner.grid, planner.fields, planner.channels, 10.0)[0]
    wings = layers["flare.irradiance"] - ghosts.mean(axis=-1)
    # 8 px from the sun: the Airy pattern's ring-averaged far wings, 1 / ((λN)² x³) per µm² at x = π r / λN, times the
    # sun's light (25 px of 5000) and the pixel's area, within a factor 1.5 (the sun spans 5 px); far from it the sky's
    # own wings (0.2 x the share each pixel gives, brought back from its neighbours)
    lam_n, pitch = starburst["wavelength_nm"] * 1e-3 * starburst["f_number"], starburst["pitch_um"]
    x = math.pi * 8 * pitch / lam_n
    assert wings[60, 208] / (25 * 5000.0 * pitch**2 / (lam_n**2 * x**3)) == pytest.approx(1.0, abs=0.5)
    assert wings[200, 40] == pytest.approx(0.2 * starburst["wings"], rel=0.2)
