"""`camera`'s scene input: a Mitsuba scene file rendered over the sensor's exposure windows (`rendered`) in place
of an irradiance image, its emitters named as PWM-driven (`--pwm-emitter`) and its camera moving during the
frame (`--camera-motion`).

The windows are the sensor's: its `[sensor.shutter]` (global without one) and `--exposure-ms`. A moving camera is
given as a simulator gives it: the camera's velocity (world units per second) and angular velocity (degrees per
second about the world's axes through the camera), constant over the frame, so the scene's camera pose is the
frame's start (the first row's) and `poses.end_pose` its pose at the frame's end (the last row's end); `rendered`
interpolates between them, which for a constant angular velocity is its rotation exactly (a spherical
interpolation about one axis, `poses`). Nothing here imports Mitsuba or NumPy at import.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from typing import Any

from ..errors import SolasError
from ..render.mitsuba import SCENE_SUFFIXES
from .poses import MAX_TURN_DEG

PWM_FORM = "ID,HZ,DUTY[,PHASE]"  # --pwm-emitter: an emitter's id (or its shape's) and its PWM source's values
MOTION_FORM = "VX,VY,VZ[,WX,WY,WZ]"  # --camera-motion: velocity and angular velocity
SPEED_UNIT, TURN_UNIT = "world units/s", "deg/s"
# the parts a render in time keeps (`rendered.RenderedParts`: float32 per slice and PWM emitter) and the rows' sum
# (float64), per pixel and channel of the film (counted as 4: R, G, B, A)
PART_BYTES, SUM_BYTES, FILM_CHANNELS = 4.0, 8.0, 4


def is_scene(path) -> bool:
    """A Mitsuba scene file (`render.mitsuba.SCENE_SUFFIXES`): `camera`'s input rendered instead of read."""
    return str(path).lower().endswith(SCENE_SUFFIXES)


def parse_pwm_emitter(text: str) -> tuple[str, Any]:
    """The emitter's name and its `timing.PWMSource` of a `PWM_FORM` text, e.g. ``"tail_light,90,0.1,0.5"``."""
    from .timing import PWMSource

    name, _, rest = text.partition(",")
    try:
        numbers = [float(p) for p in rest.split(",")]
    except ValueError:
        numbers = []
    if not name or not 2 <= len(numbers) <= 3:
        raise SolasError(
            f"--pwm-emitter {text!r} must be {PWM_FORM}: an emitter's id (or its shape's) in the scene, the PWM "
            "frequency (Hz), duty cycle and phase (fractions)"
        )
    try:
        return name, PWMSource(*numbers)
    except SolasError as exc:
        raise SolasError(f"--pwm-emitter {text!r}: {exc}") from None


def parse_motion(text: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The velocity and angular velocity (0 0 0 when not given) of a `MOTION_FORM` text."""
    try:
        numbers = tuple(float(p) for p in text.split(","))
    except ValueError:
        numbers = ()
    if len(numbers) not in (3, 6) or not all(math.isfinite(v) for v in numbers):
        raise SolasError(
            f"--camera-motion {text!r} must be {MOTION_FORM}: the camera's velocity in {SPEED_UNIT} and its angular "
            f"velocity in {TURN_UNIT} about the world's x, y, z axes, three or six finite numbers"
        )
    return numbers[:3], (numbers[3:] or (0.0, 0.0, 0.0))


@dataclass(frozen=True)
class SceneTiming:
    """A scene file's light and camera over the frame (the options --pwm-emitter, --camera-motion): its PWM emitters
    by name, ((name, `timing.PWMSource`), ...), and its camera's velocity (`SPEED_UNIT`; None: still) and angular
    velocity (`TURN_UNIT` about the world's axes through the camera), constant over the frame."""

    pwm: tuple = ()
    velocity: tuple[float, ...] | None = None
    angular_deg_s: tuple[float, ...] = (0.0, 0.0, 0.0)

    def describe(self) -> dict:
        """For metadata and a batch's identity: the PWM sources by name and the camera's motion (None: still)."""
        motion = (
            None if self.velocity is None else {"velocity": self.velocity, "angular_velocity_deg_s": self.angular_deg_s}
        )
        return {"pwm_emitters": {name: vars(source) for name, source in self.pwm}, "camera_motion": motion}

    def parts(self, shutter) -> int:
        """The parts its render takes under `shutter` (None: global): each time slice with the PWM emitters off
        and each alone (`rendered.render_parts`)."""
        from .timing import Shutter

        return ((shutter or Shutter()).time_samples if self.velocity is not None else 1) * (1 + len(self.pwm))

    def parts_bytes(self, shutter, rows: int, cols: int) -> float:
        """The memory of its render's parts and their sum (bytes) for a film of `rows` × `cols` under `shutter`."""
        return (self.parts(shutter) * PART_BYTES + SUM_BYTES) * FILM_CHANNELS * rows * cols

    def render(self, scene, spp: int, shutter, exposure_s: float, seed: int):
        """The loaded `scene` rendered over the rows' windows (`rendered.render_in_time`), its camera's end pose
        the one its motion reaches over the frame's span (`poses.end_pose`); its meta's ``exposure_windows`` adds
        the motion."""
        from .poses import camera_pose, end_pose
        from .rendered import render_in_time
        from .timing import Shutter

        end = None
        if self.velocity is not None:
            rows = int(scene.sensors()[0].film().size()[1])  # the whole film's
            span = float((shutter or Shutter()).windows(rows, exposure_s)[1].max())
            end = end_pose(camera_pose(scene.sensors()[0])[1], self.velocity, self.angular_deg_s, span)
        result = render_in_time(scene, spp, shutter, exposure_s, dict(self.pwm), end, seed)
        result.meta["exposure_windows"]["camera_motion"] = self.describe()["camera_motion"]
        return result


def scene_timing(pwm_emitters, camera_motion) -> SceneTiming | None:
    """The `SceneTiming` of the texts of --pwm-emitter (a list or None) and --camera-motion (or None); None
    without either."""
    if not pwm_emitters and camera_motion is None:
        return None
    pwm = tuple(parse_pwm_emitter(text) for text in pwm_emitters or [])
    if len({name for name, _ in pwm}) < len(pwm):
        raise SolasError(f"--pwm-emitter names an emitter twice ({', '.join(n for n, _ in pwm)}); give each once")
    if camera_motion is None:
        return SceneTiming(pwm)
    return SceneTiming(pwm, *parse_motion(camera_motion))


def check_scene_options(args: argparse.Namespace) -> None:
    """Refuse options that go with the other kind of input: --pwm-emitter, --camera-motion, --spp, --set need a scene,
    --flicker and --image-motion an image (a scene's emitters and camera move themselves)."""
    scene = is_scene(args.image)
    wrong = (
        [f for f, v in (("--flicker", args.flicker), ("--image-motion", args.image_motion)) if v is not None]
        if scene
        else [
            f
            for f, v in (
                ("--pwm-emitter", args.pwm_emitter),
                ("--camera-motion", args.camera_motion),
                ("--spp", args.spp),
                ("--set", args.set),
            )
            if v is not None  # given, even as 0 or empty: refused, not dropped
        ]
    )
    if wrong and scene:
        raise SolasError(
            f"{' and '.join(wrong)} go(es) with an image input (EXR), and {args.image} is a scene: its emitters take "
            "--pwm-emitter and its camera --camera-motion"
        )
    if wrong:
        raise SolasError(
            f"{' and '.join(wrong)} go(es) with a scene input ({', '.join(SCENE_SUFFIXES)}); {args.image} is not one"
        )


def rendered_input(args: argparse.Namespace, shutter, exposure_s: float | None, camera_bytes):
    """The R, G, B image (H, W, 3, float64) each row of the scene file `args.image` gathers over its window, and
    its metadata (the render's, its f-number where its camera is a lens camera, and `exposure_windows`); the
    memory checked first: the render's, its parts' and the camera's (`camera_bytes(rows, cols)`)."""
    import numpy as np

    from ..imageio import check_finite
    from ..render.commands import check_render, scene_params
    from ..render.user_scene import load
    from .timing import Shutter

    if exposure_s is None:
        raise SolasError("--exposure-ms auto: a scene is rendered over the exposure's windows; give a time in ms")
    timing = scene_timing(args.pwm_emitter, args.camera_motion) or SceneTiming()
    scene = load(args.image, params=scene_params(args.set))
    film = scene.sensors()[0].film()
    cols, rows = (int(v) for v in film.crop_size())
    spp = args.spp if args.spp is not None else int(scene.sensors()[0].sampler().sample_count())
    check_render(cols, rows, spp, args.force)
    shutter = shutter or Shutter()
    parts = timing.parts_bytes(shutter, rows, cols)
    from ..budget import check_memory

    check_memory(
        f"camera {cols}x{rows} of a scene in time", parts + camera_bytes(rows, cols), args.force, "a smaller film"
    )
    result = timing.render(scene, spp, shutter, exposure_s, args.seed)
    missing = [c for c in "RGB" if c not in result.channels]
    if missing:
        raise SolasError(
            f"{args.image}: its film gives channels {', '.join(result.channels)}; the sensor needs R, G, B"
        )
    image = np.stack([result.image[..., result.channels.index(c)] for c in "RGB"], axis=-1).astype(np.float64)
    check_finite(image, f"{args.image} rendered over the exposure windows")
    meta = dict(result.meta, scene=str(args.image))
    if type(scene.sensors()[0]).__name__ == "LensCamera":
        from ..render.user_scene import camera_meta

        meta.update(lens=scene.sensors()[0].lens.name, **camera_meta(scene))
    return image, meta


def add_scene_options(p: Any) -> None:
    """--spp, --set, --pwm-emitter, --camera-motion: a scene input's render over the exposure windows."""
    p.add_argument(
        "--spp", type=int, help="with a scene input: samples per pixel of each part rendered (default: the scene's)"
    )
    from ..render.commands import add_set_option

    add_set_option(p, "with a scene input: ")
    add_timing_options(p, "with a scene input")


def add_timing_options(p: Any, where: str) -> None:
    """--pwm-emitter and --camera-motion (`SceneTiming`), their help opening with `where` they apply."""
    from .rendered import INDEX

    p.add_argument(
        "--pwm-emitter",
        action="append",
        metavar=PWM_FORM,
        help=f"{where}: the emitter of id ID (or of the shape of id ID, for an area light, or {INDEX}N: the scene's "
        "N-th emitter from 0, for one without an id) is driven by pulse-width modulation at HZ with duty cycle DUTY "
        "and phase PHASE (fractions; default phase 0): it is rendered alone and each row gathers its light over the "
        "time it is on within the row's window, e.g. an LED traffic light; repeatable (default: none)",
    )
    p.add_argument(
        "--camera-motion",
        metavar=MOTION_FORM,
        help=f"{where}: the scene's camera moves at VX, VY, VZ {SPEED_UNIT} and turns at WX, WY, WZ {TURN_UNIT} about "
        "the world's axes through itself (default 0) during the frame, from its pose in the scene at the first row's "
        "start: each row sees it over its window (a rolling shutter skews, every shutter blurs; the shutter's "
        f"time_samples poses; less than {MAX_TURN_DEG:g}° over the frame) (default: still)",
    )
