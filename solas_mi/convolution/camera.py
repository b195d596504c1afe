"""The camera a degraded frame was taken with, as every output records it (`frame_camera`): the lens, its
sensor, pitch and focus and the fitted calibration of a camera model (`optics.calibration.describe_camera`).

A pinhole frame (or an image spanning the grid's field) comes out of `degrade` with the lens's distortion:
each direction lands where the lens's chief ray at the grid's reference wavelength lands (`mapping`), on a
sensor of the pinhole camera's pitch (`kernels.grid_camera`: the pinhole focal length over fx) with the axis
at the frame's principal point. So its camera is the lens's chief-ray mapping over that sensor, fitted like
`solas-mi lens calibrate`. An image already in the lens's own projection (a grid laid out on the sensor) keeps
it: the same, at the grid's sensor pitch. A fisheye frame (`--fisheye`) keeps its own camera: its points are
the reference wavelength's chief rays already, so its calibration is the one it was given.

A fit costs seconds (2–6 s for the shipped lenses): a batch makes it once per frame size (`frame_cameras`),
never per frame, and `describe_camera` keeps each block in the cache of fitted cameras, so a later degrade of
a frame of the same camera reads it back.
"""

from __future__ import annotations

from ..errors import SolasError

# memory of a fit (bytes): Dr.Jit's LLVM backend, SciPy and the tracer stay resident after it (measured 121-168 MB
# more resident after a fit, over 320x216 to 4000x3000 sensors), and its residual over every pixel (a float64 map
# and a block's pixel positions and directions: the peak grew by 17 B a pixel at 4000x3000)
FIT_FIXED_BYTES, FIT_PIXEL_BYTES = 180e6, 20


def grid_lens(grid):
    """The lens a PSF grid (or a grid over object distance) was computed from, read again from the file or
    shipped name its metadata names (`lens_source`, `lens`) where it still has the grid's `lens_hash`; None
    where neither does (a lens scaled in memory, a file since changed or moved)."""
    from ..optics.lens import Lens

    first = getattr(grid, "layers", [grid])[0]
    want = grid.meta.get("lens_hash")
    for name in (first.meta.get("lens_source"), grid.meta.get("lens")):
        if not name or not want:
            continue
        try:
            lens = Lens.load(name)
        except (SolasError, OSError):
            continue
        if lens.hash == want:
            return lens
    return None


def fit_bytes(pixels: int) -> float:
    """Memory (bytes) a fit over a sensor of `pixels` adds to a process that has not fitted one yet."""
    return FIT_FIXED_BYTES + FIT_PIXEL_BYTES * pixels


def frame_fit_bytes(grid, width: int, height: int, frame=None, model: str | None = None) -> float:
    """Memory (bytes) `frame_camera` of these arguments adds: `fit_bytes` of the frame, none where it fits nothing
    (no model, a fisheye frame, a grid whose lens is gone) or reads its block back from the cache of fitted cameras
    (`optics.calibration.camera_cached`)."""
    from ..optics.calibration import camera_cached

    sensor = None if model is None else frame_sensor(grid, width, height, frame)
    lens = None if sensor is None else grid_lens(grid)
    if lens is None or camera_cached(lens, sensor, model, wavelength_nm=reference_wavelength(grid)):
        return 0.0
    return fit_bytes(width * height)


def reference_wavelength(grid) -> float:
    """The wavelength (nm) of the chief rays degrade's mapping follows (`mapping.reference_index`)."""
    from .mapping import reference_index

    first = getattr(grid, "layers", [grid])[0]
    return float(first.wavelengths_nm[reference_index(first)])


def frame_sensor(grid, width: int, height: int, frame=None):
    """The sensor (`optics.calibration.Sensor`) degrade puts a width×height frame of camera `frame` on (None: one
    spanning the grid's x field), or None for a fisheye frame, which keeps its own camera; SolasError where the
    grid does not take the frame (`kernels.layout`)."""
    from ..optics.calibration import Sensor
    from ..optics.frame import FISHEYE
    from .curved import frame_layout

    first = getattr(grid, "layers", [grid])[0]
    if frame is not None and frame.model in FISHEYE and first.meta.get("layout") != "sensor":
        return None
    camera = frame_layout(first, width, height, frame).camera
    return Sensor(int(width), int(height), float(camera.pitch_um), camera.centre)


def frame_camera(grid, width: int, height: int, frame=None, model: str | None = None, lens=None) -> dict:
    """The camera block of a width×height frame degraded by `grid` (taken by `frame`, `optics.frame.FrameCamera`;
    None: spanning the grid's x field): lens, sensor, pitch, focus and `model` (`optics.calibration.MODELS`;
    None: none) fitted to `lens` (None: `grid_lens`) over its `frame_sensor` (module docstring)."""
    return _block(grid, width, height, frame, frame_sensor(grid, width, height, frame), model, lens)


def _block(grid, width: int, height: int, frame, sensor, model: str | None, lens) -> dict:
    """`frame_camera` on the frame's `sensor` (None: a fisheye frame's own camera)."""
    from ..optics.calibration import describe_camera

    named = {
        "lens": grid.meta.get("lens"),
        "lens_hash": grid.meta.get("lens_hash"),
        "wavelength_nm": reference_wavelength(grid),
    }
    if sensor is None:
        return {
            **named,
            "frame_camera": frame.meta(width, height),
            "frame": "the frame's own camera, kept: its points are the lens's chief rays at wavelength_nm",
        }
    lens = grid_lens(grid) if lens is None else lens
    frame_note = (
        "the lens's chief-ray mapping at wavelength_nm over this sensor (its distortion kept; the axis at principal_px)"
    )
    if lens is None:
        return {
            **named,
            **sensor.describe(),
            "frame": frame_note,
            "calibration": None,
            "no_calibration": "the grid's lens file (lens_source) is gone or changed: no lens to fit; degrade a "
            "grid of a lens that is still there",
        }
    return {**describe_camera(lens, sensor, model, wavelength_nm=named["wavelength_nm"]), "frame": frame_note}


def frame_cameras(grid, sizes, frame=None, model: str | None = None, lens=None) -> dict[str, dict]:
    """`frame_camera` of each frame size (width, height) of `sizes`, each once: "WxH" → its block; a size the
    grid does not take is left out (its frames fail on their own, saying why); a model that cannot hold the
    field is refused (SolasError)."""
    out = {}
    for w, h in sorted(set(sizes)):
        try:
            sensor = frame_sensor(grid, w, h, frame)
        except SolasError:
            continue
        out[f"{w}x{h}"] = _block(grid, w, h, frame, sensor, model, lens)
    return out
