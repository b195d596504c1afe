"""`Camera`: the sensor and image processor every frame of a batch goes through, and how a frame is
shot: the RAW of frame `name` (the item's output name) from the camera's seed and that name, so that
a frame comes out the same whatever the order of the run, a resumed run or a Dask worker. A frame's
values times `scale` are read as `solas-mi camera` reads them: image irradiance (W/m²), or radiance
through the f-number the frame states (a render through a lens); the exposure is given, or chosen per
frame from its light (`sensor.auto_exposure`).

The sensor's fixed pattern (PRNU, DSNU) comes from the seed alone, as one camera's would; the
temporal noise from (seed, frame number), the frame number a hash of the frame's name."""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import SolasError
from ..sensor.auto_exposure import AUTO, AutoExposure, exposure_seconds
from ..sensor.capture import check_seed
from ..sensor.chain import SensorChain
from ..sensor.model import SensorModel
from ..sensor.scene_input import SceneTiming
from ..sensor.timing import SceneInTime
from .pipeline import ISP, check_sensor


@dataclass(frozen=True)
class Camera:
    """The sensor and image processor every frame of a batch goes through, and how a frame is shot.

    Parameters
    ----------
    sensor : SensorModel or SensorChain
        The sensor (an HDR sensor's chain of stages too).
    exposure_ms : float or AutoExposure
        The exposure time (ms), or an `sensor.auto_exposure.AutoExposure` (chosen per frame from its light).
    isp : ISP, optional
        The image processor; None: RAW only.
    seed : int, default 0
        The sensor's seed (its fixed pattern); each frame's temporal noise also takes the frame's name.
    scale : float, default 1.0
        A frame's values times `scale` are image irradiance in W/m² (radiance through the f-number a frame
        states, for a render through a lens).
    scene_in_time : sensor.timing.SceneInTime, optional
        Each frame made a scene in time: a box of PWM-driven light, or the image's motion; none: still.
    scene_timing : sensor.scene_input.SceneTiming, optional
        A scene file's PWM emitters and camera motion: a batch's scene items rendered over this camera's
        exposure windows (its sensor's shutter and exposure); none: rendered still.

    Raises
    ------
    SolasError
        For a value of the wrong kind, a non-positive exposure or scale, a bad seed, or a scene timing with a scene
        in time or an automatic exposure.

    Examples
    --------
    >>> import numpy as np
    >>> from solas_mi.isp import load_camera
    >>> raw, frame, meta = load_camera("ar0132at", 10.0, "default", seed=3).shoot(np.full((8, 12, 3), 0.2), "f1")
    >>> raw.shape, frame.shape, meta["exposure_ms"]
    ((8, 12), (8, 12, 3), 10.0)
    """

    sensor: SensorModel | SensorChain
    exposure_ms: float | AutoExposure
    isp: ISP | None = None
    seed: int = 0
    scale: float = 1.0
    scene_in_time: SceneInTime | None = None
    scene_timing: SceneTiming | None = None

    def __post_init__(self):
        if not isinstance(self.sensor, (SensorModel, SensorChain)):
            raise SolasError(
                f"camera sensor {self.sensor!r} must be a solas_mi.sensor.model.SensorModel or a "
                "solas_mi.sensor.chain.SensorChain"
            )
        if not isinstance(self.exposure_ms, AutoExposure) and (
            isinstance(self.exposure_ms, bool)
            or not isinstance(self.exposure_ms, (int, float))
            or not math.isfinite(self.exposure_ms)
            or self.exposure_ms <= 0
        ):
            raise SolasError(f"exposure {self.exposure_ms!r} ms must be a finite number > 0 or an AutoExposure")
        if isinstance(self.scale, bool) or not isinstance(self.scale, (int, float)) or not 0 < self.scale < math.inf:
            raise SolasError(f"camera scale {self.scale!r} must be a finite number > 0 (W/m² per unit of a frame)")
        if self.isp is not None and not isinstance(self.isp, ISP):
            raise SolasError(f"camera isp {self.isp!r} must be a solas_mi.isp.pipeline.ISP or None")
        if self.isp is not None:
            check_sensor(self.isp, self.sensor)
        check_seed(self.seed)
        if self.scene_in_time is not None and not isinstance(self.scene_in_time, SceneInTime):
            raise SolasError(
                f"camera scene_in_time {self.scene_in_time!r} must be a solas_mi.sensor.timing.SceneInTime"
            )
        if self.scene_timing is not None:
            check_scene_timing(self)

    def describe(self) -> dict:
        """Every value as JSON values: for metadata, manifests and the batch's identity.

        Returns
        -------
        dict
            The sensor's parameters, the exposure (and the automatic exposure's), scale, seed and processor.
        """
        from ..sensor.files import describe

        auto = self.exposure_ms if isinstance(self.exposure_ms, AutoExposure) else None
        return {
            "sensor": describe(self.sensor),
            "exposure_ms": AUTO if auto is not None else self.exposure_ms,
            **({"auto_exposure": auto.describe()} if auto is not None else {}),
            "scale": self.scale,
            "seed": self.seed,
            "isp": None if self.isp is None else self.isp.describe(),
            **({} if self.scene_in_time is None else self.scene_in_time.describe()),
            **({} if self.scene_timing is None else {"scene_timing": self.scene_timing.describe()}),
        }

    def shoot(self, irradiance: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray | None, dict]:
        """Shoot one frame: the RAW of an irradiance image, and the developed frame.

        Parameters
        ----------
        irradiance : numpy.ndarray
            (H, W, 3) values, times `scale` image irradiance in W/m².
        name : str
            The frame's name: with the seed it fixes the frame's noise, whatever the order of a run.

        Returns
        -------
        raw : numpy.ndarray
            (H, W) DN: uint16, or uint32 for an HDR sensor's merged signal not companded.
        frame : numpy.ndarray or None
            The developed (H, W, 3) uint8 frame; None without an image processor.
        meta : dict
            The camera, the frame's name and number, its exposure, the stages.
        """
        from ..sensor.capture import as_chain, capture
        from .pipeline import develop

        number = frame_number(name)
        seconds, chosen = exposure_seconds(self.exposure_ms, self.sensor, irradiance)
        scene = irradiance if self.scene_in_time is None else self.scene_in_time.of(irradiance)
        raw = capture(self.sensor, scene, seconds, self.seed, number)
        meta = {
            "kind": "sensor RAW",
            "unit": "DN",
            "camera": self.describe(),
            "frame": name,
            "frame_number": number,
            "exposure_ms": seconds * 1e3 if chosen else self.exposure_ms,
            **({"auto_exposure": chosen} if chosen else {}),
        }
        if self.isp is None:
            return raw, None, meta
        defective = as_chain(self.sensor).defective_pixels(raw.shape, self.seed)
        frame, developed = develop(raw, self.sensor, self.isp, defective)
        return raw, frame, {**meta, **developed}


def check_scene_timing(camera: Camera) -> None:
    """Refuse a camera's scene timing of the wrong kind, with a scene in time, or with an automatic exposure."""
    if not isinstance(camera.scene_timing, SceneTiming):
        raise SolasError(
            f"camera scene_timing {camera.scene_timing!r} must be a solas_mi.sensor.scene_input.SceneTiming"
        )
    if camera.scene_in_time is not None:
        raise SolasError(
            "a camera's --pwm-emitter and --camera-motion (a scene file's) go without --flicker and --image-motion "
            "(an image's)"
        )
    if isinstance(camera.exposure_ms, AutoExposure):
        raise SolasError(
            "--exposure-ms auto: a scene file is rendered over the exposure's windows (--pwm-emitter, "
            "--camera-motion); give a time in ms"
        )


def frame_number(name: str) -> int:
    """The frame number of the frame named `name` (56 bits of its SHA-256)."""
    return int.from_bytes(hashlib.sha256(name.encode()).digest()[:7], "little")


def camera_outputs(output: str | Path, camera: Camera | None) -> list[str]:
    """The files the camera adds beside an item's output OUT/<name>.exr: OUT/<name>_raw.exr, and with an
    image processor the developed frame OUT/<name>_raw.png beside it (as `solas-mi camera` names it)."""
    if camera is None:
        return []
    raw = Path(output).with_name(Path(output).stem + "_raw.exr")
    return [str(raw)] + ([str(raw.with_suffix(".png"))] if camera.isp is not None else [])


def write_frame(raw_path: str | Path, raw: np.ndarray, frame: np.ndarray | None, meta: dict) -> None:
    """The RAW EXR (channel RAW, DN) and the developed frame's PNG beside it, together or neither."""
    from ..imageio import write_exr, write_png
    from ..outputs import written_together

    paths = [Path(raw_path)] + ([Path(raw_path).with_suffix(".png")] if frame is not None else [])
    if frame is not None:
        meta = {**meta, "developed_frame": paths[1].name}
    with written_together(*paths) as tmps:
        write_exr(tmps[0], {"RAW": raw.astype(np.float32)}, meta)
        if frame is not None:
            write_png(tmps[1], frame / 255.0, encoded=True)


def load_camera(
    sensor_model: str,
    exposure_ms: float | AutoExposure,
    isp: str | None = None,
    seed: int = 0,
    scale: float = 1.0,
    scene_in_time: SceneInTime | None = None,
    scene_timing: SceneTiming | None = None,
) -> Camera:
    """A camera as the command line gives it (--sensor-model, --exposure-ms, --isp, --seed, --scale, --flicker or
    --image-motion, --pwm-emitter and --camera-motion).

    Parameters
    ----------
    sensor_model : str
        A sensor preset's name or a TOML file (`sensor.files.load_sensor`).
    exposure_ms : float or AutoExposure
        The exposure time (ms), or an automatic exposure.
    isp : str, optional
        "default" or an ISP TOML file (`pipeline.load_isp`); None: RAW only.
    seed : int, default 0
        The sensor's seed.
    scale : float, default 1.0
        A frame's values times `scale` are W/m².
    scene_in_time : sensor.timing.SceneInTime, optional
        A box of PWM-driven light, or the image's motion (`sensor.time_options.timed_scene`).
    scene_timing : sensor.scene_input.SceneTiming, optional
        A scene file's PWM emitters and camera motion (`sensor.scene_input.scene_timing`).

    Returns
    -------
    Camera
        The camera, checked.
    """
    from ..sensor.files import load_sensor
    from .pipeline import load_isp

    isp_model = None if isp is None else load_isp(isp)
    return Camera(load_sensor(sensor_model), exposure_ms, isp_model, seed, scale, scene_in_time, scene_timing)
