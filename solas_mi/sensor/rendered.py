"""A Mitsuba scene rendered over the sensor's exposure windows (`timing.Shutter`): PWM-driven emitters and a
camera that moves during the frame.

PWM emitters are named by id in a table beside the scene, {id: `timing.PWMSource`}: an emitter's own id, or
for an area light the id of its shape, or "#N" for the scene's N-th emitter (one without an id). (Mitsuba refuses a property its plugin does not read — "unreferenced
property" — so frequency, duty cycle and phase cannot travel on the emitter in the scene file or dict.)
Light transport is linear in the emitters' emission, so the scene rendered with every PWM emitter off (the
steady light) plus each PWM emitter rendered alone (every other emitter off), each weighted per row by the
time its source is on within the row's window over the exposure (`timing.slice_shares`), is the light each
row gathers over its window: exactly the closed-form on-time of `PWMSource.on_time`, under a global or a
rolling shutter, whatever the integrator. An emitter is switched off by scaling its emission by `OFF`
(2⁻¹⁰⁰) through `mitsuba.traverse` (`EMISSION`) and back on by restoring it, so the scene is loaded once.

A moving camera: the scene's camera (any sensor whose `to_world` is a parameter: `perspective`,
`lens_camera`, …) has its own `to_world` at the frame's start (the first row's start) and `to_world_end` at
its end (the last row's end); between them its pose is interpolated (`poses.pose_at`: the rotation by spherical
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
from .poses import camera_pose, checked_end, pose_at
from .timing import PWMSource, Shutter, slice_shares

EMISSION = ("radiance", "intensity", "irradiance")  # an emitter's parameters of emitted light (or its "scale")
# the values under them that 0 switches off: a spectrum's or texture's values, and in a spectral variant the
# D65 illuminant an RGB emission multiplies (its RGB value becomes spectral coefficients, for which 0 is grey)
LEVELS = ("value", "values", "data")
# what an emitter switched off keeps of them: not 0, which Mitsuba refuses for a spectrum it samples ("no
# probability mass"); 2⁻¹⁰⁰ of an emitter's light is below float32's resolution of any other emitter's
OFF = 2.0**-100
# what is left of the switched-off emitters in a part: values within OFF·2²⁴ of the brightest part's peak are
# that remainder (a part's own light so far below another's lies beyond any sensor's 24-bit merge) and read as 0,
# so a frame whose emitters are all off is black, not ±1e-33 (negative where a colour leaves the RGB gamut)
REMAINDER = OFF * 2.0**24
INDEX = "#"  # "#N": the scene's N-th emitter (from 0), a name for one without an id (public scenes often give none)


def emitter_names(emitter) -> list[str]:
    """The names a PWM table may give an emitter: its id, and its shape's id for an area light."""
    shape = emitter.get_shape()
    return [name for name in (emitter.id(), shape.id() if shape is not None else "") if name]


def emission(emitter) -> tuple:
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
    """The index among `scene.emitters()` of each PWM emitter named in `pwm` (`emitter_names`, or `INDEX` and
    its index, for one without an id); SolasError for a name that is not one emitter's (listing them)."""
    names = [[*emitter_names(e), f"{INDEX}{i}"] for i, e in enumerate(scene.emitters())]
    found = {}
    for name in pwm:
        hits = [i for i, known in enumerate(names) if name in known]
        if len(hits) != 1:
            known = "; ".join(f"{' = '.join(n)} ({e.class_name()})" for n, e in zip(names, scene.emitters()))
            raise SolasError(
                f"PWM emitter {name!r} names {len(hits)} of the scene's emitters; it must name one by its id, its "
                f"shape's id or {INDEX} and its index (the scene's: {known or 'none'})"
            )
        found[name] = hits[0]
    return found


@dataclass
class RenderedParts:
    """A scene's light split by time slice and PWM emitter (`render_parts`), to combine over any windows.

    Parameters
    ----------
    edges : numpy.ndarray
        (K + 1,): the edges of the K time slices rendered (s, from the first row's start).
    steady : numpy.ndarray
        (K, H, W, C): each slice with the PWM emitters off.
    alone : dict of str to numpy.ndarray
        Each PWM emitter's name → (K, H, W, C): each slice with that emitter alone.
    channels : tuple of str
        The film's channel names.
    spp : int
        Samples per pixel of each part.
    seconds : float
        The time the renders took (s).
    meta : dict, optional
        The last render's metadata.
    film_rows : tuple of int, default (0, 0)
        The first row drawn (its crop window's) and the whole film's rows: a crop window's rows take the
        windows of their rows on the whole film.
    """

    edges: np.ndarray
    steady: np.ndarray
    alone: dict[str, np.ndarray]
    channels: tuple[str, ...]
    spp: int
    seconds: float
    meta: dict = field(default_factory=dict)
    film_rows: tuple[int, int] = (0, 0)  # the film's first row drawn (its crop window's) and its rows in all

    def windows(self, shutter: Shutter, exposure_s: float) -> tuple[np.ndarray, np.ndarray]:
        """The windows of the rows drawn: those of the whole film's rows (`film_rows`) its crop window draws.

        Parameters
        ----------
        shutter : Shutter
            The rows' windows.
        exposure_s : float
            The exposure time (s).

        Returns
        -------
        tuple of numpy.ndarray
            The starts and ends (s) of the rows drawn.
        """
        first, rows = self.film_rows
        drawn = slice(first, first + self.steady.shape[1])
        starts, ends = shutter.windows(max(rows, drawn.stop), exposure_s)
        return starts[drawn], ends[drawn]

    def over_windows(self, shutter: Shutter | None, exposure_s: float, sources: dict[str, PWMSource]) -> np.ndarray:
        """The image each row gathers over its window, without rendering again.

        Parameters
        ----------
        shutter : Shutter or None
            The rows' windows (None: a global shutter).
        exposure_s : float
            The exposure time (s).
        sources : dict of str to PWMSource
            The PWM source of each emitter rendered alone (the same names).

        Returns
        -------
        numpy.ndarray
            (H, W, C), float64: each row's mean over its window.

        Raises
        ------
        SolasError
            For windows past the span rendered, other names than those rendered, or a source that is not a
            `PWMSource`.
        """
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


# long: the public API's numpydoc docstring is half of it
def render_parts(
    scene, spp: int, shutter: Shutter | None, exposure_s: float, pwm=(), to_world_end=None, seed: int = 0
) -> RenderedParts:
    """Render a loaded scene's parts over a frame: each time slice with its PWM emitters off and each alone.

    Parameters
    ----------
    scene : mitsuba.Scene
        The scene (its first sensor the camera).
    spp : int
        Samples per pixel of each part.
    shutter : Shutter or None
        The rows' windows (None: a global shutter).
    exposure_s : float
        The exposure time (s, above 0).
    pwm : iterable of str, default ()
        The PWM emitters' names: an emitter's id, or an area light's shape's id.
    to_world_end : array_like, optional
        The camera's 4×4 `to_world` at the frame's end (the last row's end); default: still (one slice).
    seed : int, default 0
        The render's seed (the same for every part).

    Returns
    -------
    RenderedParts
        The parts, to combine with `RenderedParts.over_windows` for any phases and windows in the span.

    Raises
    ------
    SolasError
        For a bad exposure, a name that is not one emitter's, an emitter without a parameter of its emission,
        a camera without `to_world` or a transform that is not a finite 4×4 affine one.
    """
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
    assert result is not None  # a slice and a group at least: rendered
    stacks = {name: np.stack(v) for name, v in images.items()}
    floor = REMAINDER * max(float(np.abs(v).max(initial=0.0)) for v in stacks.values())
    for v in stacks.values():
        v[np.abs(v) <= floor] = 0.0
    return RenderedParts(
        edges,
        stacks.pop(None),
        stacks,
        result.channels,
        spp,
        time.perf_counter() - began,
        result.meta,
        (int(film.crop_offset()[1]), rows),
    )


# long: the public API's numpydoc docstring is half of it
def render_in_time(
    scene,
    spp: int,
    shutter: Shutter | None,
    exposure_s: float,
    pwm: dict[str, PWMSource] | None = None,
    to_world_end=None,
    seed: int = 0,
) -> Render:
    """Render a loaded scene as the sensor's rows see it over their windows: PWM emitters, a moving camera.

    Parameters
    ----------
    scene : mitsuba.Scene
        The scene (its first sensor the camera).
    spp : int
        Samples per pixel of each part rendered.
    shutter : Shutter or None
        The rows' windows (None: a global shutter).
    exposure_s : float
        The exposure time (s, above 0).
    pwm : dict of str to PWMSource, optional
        Each PWM emitter's name (an emitter's id, or an area light's shape's id) → its source; default none.
    to_world_end : array_like, optional
        The camera's 4×4 `to_world` at the frame's end (the last row's end; its own at the first row's start,
        interpolated between, module docstring); default: still.
    seed : int, default 0
        The render's seed.

    Returns
    -------
    render.loop.Render
        Its image each row's mean over its window (the irradiance `capture` takes, as a still one's); its
        meta's ``exposure_windows`` the shutter, exposure, sources, end pose and slices.

    Raises
    ------
    SolasError
        For what `render_parts` and `RenderedParts.over_windows` refuse.

    Examples
    --------
    >>> from solas_mi.render.mitsuba import mitsuba
    >>> from solas_mi.sensor import PWMSource, Shutter, render_in_time
    >>> mi = mitsuba()
    >>> scene = mi.load_dict({
    ...     "type": "scene",
    ...     "integrator": {"type": "direct"},
    ...     "sensor": {"type": "perspective", "film": {"type": "hdrfilm", "width": 4, "height": 4}},
    ...     "led": {  # a wall 5 units along the camera's view, facing it
    ...         "type": "rectangle",
    ...         "to_world": mi.ScalarTransform4f().translate([0, 0, 5]).rotate([1, 0, 0], 180).scale(9),
    ...         "emitter": {"type": "area", "radiance": 1.0},
    ...     },
    ... })
    >>> on = render_in_time(scene, 4, Shutter(), 5e-4, {"led": PWMSource(100.0, 0.1)})  # on over [0, 1 ms)
    >>> off = render_in_time(scene, 4, Shutter(), 5e-4, {"led": PWMSource(100.0, 0.1, phase=0.5)})
    >>> float(off.image.max()) < 1e-20 < 0.5 < float(on.image.min())  # dark in its off-time, lit in its on-time
    True
    """
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
