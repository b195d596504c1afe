"""The camera block of a degraded frame (`convolution.camera`): the lens's chief-ray mapping over the sensor
degrade's mapping puts the frame on, checked against the tracer's own chief rays (`optics.pupil.chief_rays`)
and against where degrade's mapping puts each node of the grid."""

import json

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.convolution.camera import frame_camera, grid_lens
from solas_mi.convolution.curved import frame_layout
from solas_mi.convolution.mapping import reference_index
from solas_mi.optics.calibration.models import model
from solas_mi.optics.frame import FrameCamera
from solas_mi.optics.pupil import chief_rays
from solas_mi.psf.grid import psf_grid
from solas_mi.psf.spec import GridSpec

W, H = 320, 216
MODEL = "opencv-fisheye"


@pytest.fixture(scope="module")
def wide():
    """wide-angle-22mm over ±40° x ±29° at its primary wavelength (geometric PSFs: only the chief rays matter)."""
    lens = Lens.load("wide-angle-22mm")
    return psf_grid(
        lens,
        GridSpec(
            grid=(11, 9),
            size=21,
            method="geometric",
            rays=16,
            field_sampling="edges",
            wavelengths_nm=(lens.primary_wavelength,),
            field_range_deg=(40.0, 29.0),
            pitch_um=8.0,
        ),
    )


def node_pixels(grid, frame=None) -> np.ndarray:
    """Where degrade's mapping puts each node's field in the degraded frame (ny, nx, 2): its ideal pixel
    moved by its chief ray's offset (`kernels.layout`)."""
    lay = frame_layout(grid, W, H, frame)
    knots = np.stack(np.meshgrid(lay.col_knots, lay.row_knots), axis=-1)
    return knots + lay.offsets[reference_index(grid)]


def traced_pixels(lens, fields_deg, wavelength, block) -> np.ndarray:
    """The tracer's chief rays of `fields_deg` (n, 2) on the block's sensor, in pixels."""
    c = chief_rays(lens, fields_deg, np.full(len(fields_deg), wavelength))
    cx, cy = block["principal_px"]
    px = block["pitch_um"] * 1e-3
    return np.stack([cx + c.image_xy[:, 0] / px, cy - c.image_xy[:, 1] / px], axis=-1)


@pytest.mark.parametrize(
    "frame",
    [None, FrameCamera("pinhole", intrinsics=(230.0, 230.0, 166.0, 101.5))],
    ids=["field", "intrinsics-off-centre"],
)
def test_the_camera_block_is_the_mapping_degrade_applies(wide, frame):
    """The block's sensor (pitch, principal point) is the one degrade's mapping puts the frame on: every
    node lands where the tracer's chief ray of its field lands on it (to 1e-6 px); and its fitted model
    projects each node's direction there within the residual it reports."""
    lens = Lens.load("wide-angle-22mm")
    block = frame_camera(wide, W, H, frame, MODEL)
    cal = block["calibration"]
    fields = np.asarray(wide.fields_deg).reshape(-1, 2)
    traced = traced_pixels(lens, fields, block["wavelength_nm"], block)
    assert np.abs(node_pixels(wide, frame).reshape(-1, 2) - traced).max() < 1e-6
    t = np.tan(np.radians(fields))
    xyz = np.stack([t[:, 0], -t[:, 1], np.ones(len(t))], axis=-1)  # x right, y down, z forward
    inside = (traced[:, 0] >= 0) & (traced[:, 0] <= W - 1) & (traced[:, 1] >= 0) & (traced[:, 1] <= H - 1)
    error = np.hypot(*(model(MODEL).project(cal["parameters"], xyz) - traced).T)[inside]
    assert inside.sum() > 20 and error.max() <= cal["max_residual_px"] + 1e-6
    expected = list(frame.pinhole(W, H)[2:]) if frame is not None else [(W - 1) / 2, (H - 1) / 2]
    assert block["principal_px"] == pytest.approx(expected) and block["sensor_px"] == [W, H]
    assert block["lens_hash"] == lens.hash and json.loads(json.dumps(block)) == block


def test_a_fisheye_frame_keeps_its_own_camera():
    """A fisheye frame's points are the lens's chief rays already: its block is the frame's calibration, no fit."""
    lens = Lens.load("nikkor-fisheye")
    grid = psf_grid(
        lens,
        GridSpec(
            grid=(5, 5),
            size=21,
            method="geometric",
            rays=16,
            field_sampling="edges",
            wavelengths_nm=(lens.primary_wavelength,),
            field_range_deg=(58.0, 48.0),
            pitch_um=10.0,
        ),
    )
    frame = FrameCamera(
        "kannala-brandt", intrinsics=(180.0, 180.0, W / 2 - 0.5, H / 2 - 0.5), coefficients=(-0.02, 0.003, 0.0, 0.0)
    )
    block = frame_camera(grid, W, H, frame, MODEL)
    assert block["frame_camera"] == frame.meta(W, H) and "calibration" not in block


def test_a_grid_whose_lens_is_gone_says_so(wide, tmp_path):
    """The lens is read again from the grid's lens_source only while it is the grid's lens (same hash); where it
    is not, the block has the sensor and no calibration, and says why."""
    assert grid_lens(wide).hash == wide.meta["lens_hash"]
    changed = tmp_path / "wide.toml"
    Lens.load("solas-doublet").save(changed)  # the grid's lens file, since overwritten
    wide.meta.update(lens_source=str(changed), lens="another")
    try:
        block = frame_camera(wide, W, H, None, MODEL)
    finally:
        wide.meta.update(lens_source=Lens.load("wide-angle-22mm").source, lens="wide-angle-22mm")
    assert block["calibration"] is None and "lens_source" in block["no_calibration"]
    assert block["pitch_um"] == frame_camera(wide, W, H, None, None)["pitch_um"]


def test_a_sensors_principal_point_is_two_finite_numbers():
    """A calibration sensor's axis lands at its principal point: the table of chief rays reaches its farthest
    corner from there; a principal point that is not two finite numbers is refused by name."""
    import math

    from solas_mi import SolasError
    from solas_mi.optics.calibration import Sensor

    assert Sensor(10, 8, 5.0, (2.0, 1.0)).reach_px() == pytest.approx(math.hypot(7, 6))
    assert Sensor(10, 8, 5.0).centre == (4.5, 3.5)
    for bad in ((math.nan, 0.0), (1.0,), ("a", 2.0)):
        with pytest.raises(SolasError, match="principal point"):
            Sensor(10, 8, 5.0, bad)
