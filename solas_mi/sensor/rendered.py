"""A Mitsuba scene rendered over the sensor's exposure windows (`timing.Shutter`): PWM-driven emitters and a
camera that moves during the frame.

PWM emitters are named by id in a table beside the scene, {id: `timing.PWMSource`}: an emitter's own id, or
for an area light the id of its shape. (Mitsuba refuses a property its plugin does not read — "unreferenced
property" — so frequency, duty cycle and phase cannot travel on the emitter in the scene file or dict.)
Light transport is linear in the emitters' emission, so the scene rendered with every PWM emitter off (the
steady light) plus each PWM emitter rendered alone (every other emitter off), each weighted per row by the
time its source is on within the row's window over the exposure (`timing.slice_shares`), is the light each
row gathers over its window: exactly the closed-form on-time of `PWMSource.on_time`, under a global or a
rolling shutter, whatever the integrator. An emitter is switched off by scaling its emission by `OFF`
(2⁻¹⁰⁰) through `mitsuba.traverse` (`EMISSION`) and back on by restoring it, so the scene is loaded once.

A moving camera: the scene's camera (any sensor whose `to_world` is a parameter: `perspective`,
`lens_camera`, …) has its own `to_world` at the frame's start (the first row's start) and `to_world_end` at
its end (the last row's end); between them its pose is interpolated (`pose_at`: the rotation by spherical
interpolation, the rest linearly). The frame's span is split into `Shutter.time_samples` even slices, each
rendered at the pose of its midpoint, and each row averages the slices its window covers, each weighted by
its share of the window: a rolling shutter's rows see the camera at their own times (skew), every row the
poses over its whole window (motion blur, of `time_samples` poses). A still camera takes one slice.

Every part (a slice with the PWM emitters off, or one PWM emitter alone) is rendered by
`render.stock.render_scene` with the same seed, so `RenderedParts.over_windows` combines them for any
phases, shutter windows within the span rendered, without rendering again.
"""

from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from ..errors import SolasError
from ..render.loop import Render
from .timing import PWMSource, Shutter, slice_shares

EMISSION = ("radiance", "intensity", "irradiance")  # an emitter's parameters of emitted light (or its "scale")
# the values under them that 0 switches off: a spectrum's or texture's values, and in a spectral variant the
# D65 illuminant an RGB emission multiplies (its RGB value becomes spectral coefficients, for which 0 is grey)
LEVELS = ("value", "values", "data")
# what an emitter switched off keeps of them: not 0, which Mitsuba refuses for a spectrum it samples ("no
# probability mass"); 2⁻¹⁰⁰ of an emitter's light is below float32's resolution of any other emitter's
OFF = 2.0**-100


def emitter_names(emitter) -> list[str]:
    """The names a PWM table may give an emitter: its id, and its shape's id for an area light."""
    shape = emitter.get_shape()
    return [name for name in (emitter.id(), shape.id() if shape is not None else "") if name]


def emission(emitter) -> tuple[object, dict]:
    """The emitter's parameters (`mitsuba.traverse`) and the values of those that scale its emission: its
    "scale" where it has one (an environment map), else its radiance, intensity or irradiance values
    (`LEVELS`)."""
    import mitsuba as mi

    params = mi.traverse(emitter)
    keys = list(params.keys())
    chosen = (
        ["scale"]
        if "scale" in keys
        else [k for k in keys if k.split(".")[0] in EMISSION and k.split(".")[-1] in LEVELS]
    )
    if not chosen:
        raise SolasError(
            f"emitter {', '.join(emitter_names(emitter)) or emitter.class_name()} ({emitter.class_name()}) has no "
            f"parameter of its emission ({', '.join(EMISSION)} or scale) to switch off and on"
        )
    # copies: the parameters hold the emitter's own values, which setting a parameter overwrites in place
    return params, {key: type(params[key])(params[key]) for key in chosen}


@contextmanager
def lit_alone(switches: list, lit: set[int]):
    """Within it, only the emitters of indices `lit` emit (`switches`: each emitter's `emission`; the others
    keep `OFF` of their light); all emit as before after it."""
    try:
        for i, (params, values) in enumerate(switches):
            for key, value in values.items():
                params[key] = value if i in lit else value * OFF
            params.update()
        yield
    finally:
        for params, values in switches:
            for key, value in values.items():
                params[key] = value
            params.update()


def pwm_indices(scene, pwm) -> dict[str, int]:
    """The index among `scene.emitters()` of each PWM emitter named in `pwm`; SolasError for a name that is
    not one emitter's (naming those there are)."""
    names = [emitter_names(e) for e in scene.emitters()]
    found = {}
    for name in pwm:
        hits = [i for i, known in enumerate(names) if name in known]
        if len(hits) != 1:
            known = sorted({n for known in names for n in known})
            raise SolasError(
                f"PWM emitter {name!r} names {len(hits)} of the scene's emitters; it must name one by its id or "
                f"its shape's id (the scene's: {', '.join(known) or 'none with an id'})"
            )
        found[name] = hits[0]
    return found


def pose_at(start: np.ndarray, end: np.ndarray, fraction: float) -> np.ndarray:
    """The 4×4 transform `fraction` of the way from `start` to `end`: the rotation of each (its polar
    decomposition's) interpolated spherically, the stretch and translation linearly; SolasError where one
    mirrors and the other does not."""
    from scipy.linalg import polar
    from scipy.spatial.transform import Rotation, Slerp

    (ra, sa), (rb, sb) = polar(start[:3, :3]), polar(end[:3, :3])
    mirror = np.diag([1.0, 1.0, np.sign(np.linalg.det(ra))])
    if np.sign(np.linalg.det(ra)) != np.sign(np.linalg.det(rb)):
        raise SolasError("the camera's to_world at the frame's start and end: one mirrors, the other does not")
    turn = Slerp([0.0, 1.0], Rotation.from_matrix([ra @ mirror, rb @ mirror]))([fraction]).as_matrix()[0]
    pose = np.eye(4)
    pose[:3, :3] = turn @ mirror @ ((1.0 - fraction) * sa + fraction * sb)
    pose[:3, 3] = (1.0 - fraction) * start[:3, 3] + fraction * end[:3, 3]
    return pose


def camera_pose(sensor) -> tuple[object, np.ndarray]:
    """The sensor's parameters (`mitsuba.traverse`) and its `to_world` (4×4); SolasError for a sensor
    without one."""
    import mitsuba as mi

    params = mi.traverse(sensor)
    if "to_world" not in params:
        raise SolasError(f"camera motion: the scene's sensor {sensor.class_name()} has no to_world parameter")
    return params, np.array(params["to_world"].matrix, dtype=np.float64).reshape(4, 4)


def checked_end(to_world_end) -> np.ndarray:
    end = np.asarray(to_world_end, dtype=np.float64)
    if end.shape != (4, 4) or not np.isfinite(end).all() or not np.allclose(end[3], [0.0, 0.0, 0.0, 1.0]):
        raise SolasError(
            f"to_world_end must be a finite 4x4 affine transform (last row 0 0 0 1), not {np.shape(to_world_end)}"
        )
    return end


@dataclass
class RenderedParts:
    """A scene's light split by time slice and PWM emitter: `edges` (K + 1, s) of the slices, `steady`
    (K, H, W, C: the PWM emitters off), `alone` (name → (K, H, W, C): that PWM emitter alone), the channels'
    names, samples per pixel, seconds, the last render's meta, and the rows of the film (a crop window's rows
    take the windows of their rows of the whole film)."""

    edges: np.ndarray
    steady: np.ndarray
    alone: dict[str, np.ndarray]
    channels: tuple[str, ...]
    spp: int
    seconds: float
    meta: dict = field(default_factory=dict)
    film_rows: tuple[int, int] = (0, 0)  # the film's first row drawn (its crop window's) and its rows in all

    def windows(self, shutter: Shutter, exposure_s: float) -> tuple[np.ndarray, np.ndarray]:
        """The windows (s) of the rows drawn: those of the whole film's rows (`film_rows`) that its crop window
        draws."""
        first, rows = self.film_rows
        drawn = slice(first, first + self.steady.shape[1])
        starts, ends = shutter.windows(max(rows, drawn.stop), exposure_s)
        return starts[drawn], ends[drawn]

    def over_windows(self, shutter: Shutter | None, exposure_s: float, sources: dict[str, PWMSource]) -> np.ndarray:
        """The image (H, W, C) each row gathers over its window, its sources at their `sources` values (the
        names rendered alone); SolasError for windows past the span rendered."""
        shutter = shutter or Shutter()
        starts, ends = self.windows(shutter, exposure_s)
        if starts.min() < self.edges[0] or ends.max() > self.edges[-1] * (1 + 1e-12):
            raise SolasError(
                f"the rows' windows ({starts.min():g} to {ends.max():g} s) reach past the time rendered "
                f"({self.edges[0]:g} to {self.edges[-1]:g} s)"
            )
        if set(sources) != set(self.alone):
            raise SolasError(f"PWM sources {sorted(sources)} must be those rendered: {sorted(self.alone)}")
        for name, source in sources.items():
            if not isinstance(source, PWMSource):
                raise SolasError(f"PWM emitter {name!r}: {source!r} must be a solas_mi.sensor.timing.PWMSource")
        total = np.einsum("kr,krwc->rwc", slice_shares(starts, ends, self.edges, exposure_s), self.steady)
        for name, images in self.alone.items():
            shares = slice_shares(starts, ends, self.edges, exposure_s, sources[name])
            total += np.einsum("kr,krwc->rwc", shares, images)
        return total


def render_parts(
    scene, spp: int, shutter: Shutter | None, exposure_s: float, pwm=(), to_world_end=None, seed: int = 0
) -> RenderedParts:
    """The parts (module docstring) of a loaded scene for a frame of `exposure_s` under `shutter` (None:
    global): the emitters named in `pwm` alone, and the camera moving to `to_world_end` (4×4; None: still)."""
    from ..render.stock import render_scene

    shutter = shutter or Shutter()
    if not (isinstance(exposure_s, (int, float)) and 0.0 < exposure_s < float("inf")):
        raise SolasError(f"exposure_s = {exposure_s!r} must be a number above 0 (s)")
    film = scene.sensors()[0].film()
    rows = int(film.size()[1])  # the whole film's: a crop window's rows keep their times
    indices = pwm_indices(scene, pwm)
    switches = [emission(e) for e in scene.emitters()] if indices else []
    if to_world_end is None:
        edges = np.array([0.0, shutter.windows(rows, exposure_s)[1].max()])
    else:
        end = checked_end(to_world_end)
        edges = shutter.slices(rows, exposure_s)
        params, start = camera_pose(scene.sensors()[0])
    steady = set(range(len(switches))) - set(indices.values())
    groups = [(None, steady)] + [(name, {i}) for name, i in indices.items()]
    images: dict = {name: [] for name, _ in groups}
    began, result = time.perf_counter(), None
    try:
        for k in range(len(edges) - 1):
            if to_world_end is not None:
                middle = 0.5 * (edges[k] + edges[k + 1]) / edges[-1]
                params["to_world"] = type(params["to_world"])(pose_at(start, end, middle))
                params.update()
            for name, lit in groups:
                with lit_alone(switches, lit):
                    result = render_scene(scene, spp, seed)
                images[name].append(result.image)
    finally:
        if to_world_end is not None:
            params["to_world"] = type(params["to_world"])(start)
            params.update()
    steady_images = np.stack(images.pop(None))
    return RenderedParts(
        edges,
        steady_images,
        {name: np.stack(v) for name, v in images.items()},
        result.channels,
        spp,
        time.perf_counter() - began,
        result.meta,
        (int(film.crop_offset()[1]), rows),
    )


def render_in_time(
    scene,
    spp: int,
    shutter: Shutter | None,
    exposure_s: float,
    pwm: dict[str, PWMSource] | None = None,
    to_world_end=None,
    seed: int = 0,
) -> Render:
    """A loaded scene as the sensor's rows see it over their windows of `exposure_s` under `shutter` (None:
    global): its emitters named in `pwm` driven by their PWM sources, the camera moving from its own
    `to_world` to `to_world_end` (4×4; None: still) over the frame (module docstring). The image is each
    row's mean over its window; the meta says the shutter, exposure, sources, motion and slices."""
    pwm = dict(pwm or {})
    parts = render_parts(scene, spp, shutter, exposure_s, pwm, to_world_end, seed)
    image = parts.over_windows(shutter, exposure_s, pwm).astype(np.float32)
    pixels = image.shape[0] * image.shape[1] * spp
    meta = {
        **parts.meta,
        "seconds": parts.seconds,
        "exposure_windows": {
            "shutter": (shutter or Shutter()).describe(),
            "exposure_s": exposure_s,
            "pwm_emitters": {name: vars(source) for name, source in pwm.items()},
            "to_world_end": None if to_world_end is None else checked_end(to_world_end).tolist(),
            "slices": len(parts.edges) - 1,
        },
    }
    return Render(image, parts.channels, spp, parts.seconds, pixels / max(parts.seconds, 1e-9), meta)
