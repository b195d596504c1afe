"""The camera's options of a still image made a scene in time (`timing.SceneInTime`): --flicker (a box of
PWM-driven light) and --image-motion (the image moving during the frame), for `camera` and a batch's camera."""

from __future__ import annotations

import argparse
import math
from typing import Any

from ..errors import SolasError

FLICKER_FORM = "X0,Y0,X1,Y1,HZ,DUTY[,PHASE]"  # the camera's --flicker: a box of pixels and its PWM source


def parse_flicker(text: str) -> tuple[tuple[int, int, int, int], tuple[float, ...]]:
    """The box (x0, y0, x1, y1) and the PWM source's values (frequency, duty cycle[, phase]) of a `FLICKER_FORM`
    text, e.g. ``"10,20,30,40,90,0.1,0.5"``."""
    parts = text.split(",")
    try:
        box = tuple(int(p) for p in parts[:4])
        numbers = tuple(float(p) for p in parts[4:])
    except ValueError:
        box, numbers = (), ()
    if len(box) != 4 or not 2 <= len(numbers) <= 3 or min(box[:2]) < 0 or box[2] <= box[0] or box[3] <= box[1]:
        raise SolasError(
            f"--flicker {text!r} must be {FLICKER_FORM}: a box of whole pixels x0 < x1, y0 < y1 "
            "from 0, the PWM frequency (Hz), duty cycle and phase (fractions)"
        )
    return (box[0], box[1], box[2], box[3]), numbers


def parse_motion(text: str) -> tuple[float, float]:
    """The velocity (px/s, right and down) of a ``VX,VY`` text."""
    try:
        velocity = tuple(float(p) for p in text.split(","))
    except ValueError:
        velocity = ()
    if len(velocity) != 2 or not all(math.isfinite(v) for v in velocity):
        raise SolasError(
            f"--image-motion {text!r} must be VX,VY: the image's speed in pixels per second, "
            "rightwards and downwards, two finite numbers"
        )
    return velocity[0], velocity[1]


def timed_scene(args: argparse.Namespace):
    """The `timing.SceneInTime` of the options --flicker and --image-motion (at most one); None without."""
    if args.flicker is None and args.image_motion is None:
        return None
    if args.flicker is not None and args.image_motion is not None:
        raise SolasError("give --flicker or --image-motion, not both: a scene in time is one or the other here")
    from .timing import PWMSource, SceneInTime

    if args.flicker is not None:
        box, source = parse_flicker(args.flicker)
        return SceneInTime(box=box, source=PWMSource(*source))
    return SceneInTime(motion_px_s=parse_motion(args.image_motion))


def add_time_options(p: Any) -> None:
    """--flicker and --image-motion: a still image made a scene in time (`timing.SceneInTime`)."""
    p.add_argument(
        "--flicker",
        metavar=FLICKER_FORM,
        help="the pixels of columns X0 to X1 - 1 and rows Y0 to Y1 - 1 are light driven by pulse-width "
        "modulation at HZ with duty cycle DUTY and phase PHASE (fractions; default phase 0): each "
        "row sees it over its window of the exposure (the sensor's [sensor.shutter], global "
        "without one), e.g. an LED traffic light (default: none)",
    )
    p.add_argument(
        "--image-motion",
        metavar="VX,VY",
        help="the image moves at VX, VY pixels per second (right, down) during the frame, e.g. a camera "
        "panning across a distant scene: each row sees it over its window of the exposure (a "
        "rolling shutter skews it, every shutter blurs it; sampled at the shutter's time_samples) "
        "(default: still)",
    )
