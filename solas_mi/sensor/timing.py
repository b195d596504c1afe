"""Exposure in time: `Shutter`, a stage of the sensor's chain (global or rolling), the light a scene gives
over each row's window of time (`exposed_irradiance`), and PWM-driven light (`PWMSource`, `FlickeringScene`).

A global shutter exposes every row over [0, t]; a rolling one starts row r after r line times L (rows read
top-down; bottom-up: row H − 1 first), so row r integrates [r L, r L + t]. A static irradiance image is the
same over every window: it passes unchanged, and a sensor without a shutter stage gives the frames it gave
before. A scene that changes during the frame is given to `capture` in one of two ways:

- a callable ``scene(t)`` of the time t (s, from the first row's start) returning an (H, W, 3) irradiance
  image (W/m²), e.g. an object moving at a known image speed: it is sampled at `Shutter.time_samples`
  instants evenly over the frame's span of time, and each row averages the samples inside its window
  (each sample weighted by the share of its interval that the window covers);
- a `FlickeringScene`: a static image plus light driven by a `PWMSource` over some pixels, whose rows'
  averages are exact (the closed-form on-time of each window).

`SceneInTime` makes a still image one of these as the `camera` command's and a batch's camera's options
say: a box of PWM-driven light (`flickering_box`) or the image moving at a velocity (`moving_image`).

A PWM source of period T, duty cycle D and phase φ (a fraction of T) is on over [φT, φT + DT) of each period.
Over uniformly random phases a window of length w overlaps its on-time by at least τ (≤ DT, w) with
probability min(1, (DT + w − 2τ)/T) (`PWMSource.visible_probability`): the on-time over a window is a
trapezoid in the phase, rising over τ, of length DT + w at its base. A rolling shutter's rows of a source
spanning n rows see the union of their windows, w = t + (n − 1) L, so the source is missed in fewer frames
than under a global shutter, but shows in bands of rows.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..errors import SolasError
from .limits import check_number

MODES = ("global", "rolling")
DIRECTIONS = ("top-down", "bottom-up")


@dataclass(frozen=True)
class Shutter:
    """How the rows take their windows of the frame's exposure: `mode` global or rolling, the rolling
    shutter's `line_time_s` (s between two rows' starts) and `direction`, and the `time_samples` at which a
    moving scene is sampled over the frame (module docstring)."""

    mode: str = "global"
    line_time_s: float = 0.0
    direction: str = "top-down"
    time_samples: int = 64

    def __post_init__(self):
        for name, allowed in (("mode", MODES), ("direction", DIRECTIONS)):
            if getattr(self, name) not in allowed:
                raise SolasError(f"sensor shutter {name} = {getattr(self, name)!r} must be one of {', '.join(allowed)}")
        check_number(
            self.line_time_s,
            "line_time_s",
            0.0,
            1.0,
            "the time between two rows' starts in s; 0 for a global shutter",
            where="sensor shutter",
        )
        if (self.mode == "rolling") != (self.line_time_s > 0):
            raise SolasError(
                f"sensor shutter line_time_s = {self.line_time_s!r}: a rolling shutter takes a line time "
                "above 0, a global one none (0)"
            )
        if (
            not isinstance(self.time_samples, int)
            or isinstance(self.time_samples, bool)
            or not 1 <= self.time_samples <= 100000
        ):
            raise SolasError(f"sensor shutter time_samples = {self.time_samples!r} must be an integer from 1 to 100000")

    def describe(self) -> dict:
        return asdict(self)

    def windows(self, rows: int, exposure_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Each row's start and end (s, from the first row's start) for an exposure of `exposure_s`."""
        order = np.arange(rows, dtype=np.float64)
        if self.direction == "bottom-up":
            order = order[::-1]
        starts = order * self.line_time_s
        return starts, starts + exposure_s

    def slices(self, rows: int, exposure_s: float) -> np.ndarray:
        """The edges (s) of the `time_samples` even slices of the frame's span of time, from the first row's
        start to the last row's end."""
        starts, ends = self.windows(rows, exposure_s)
        return np.linspace(starts.min(), ends.max(), self.time_samples + 1)

    def mean_over_windows(self, scene, rows: int, exposure_s: float) -> np.ndarray:
        """The irradiance (H, W, 3) each row of a callable `scene(t)` averages over its window (module docstring)."""
        edges = self.slices(rows, exposure_s)
        shares = slice_shares(*self.windows(rows, exposure_s), edges, exposure_s)
        total = None
        for k in range(self.time_samples):
            image = np.asarray(scene(0.5 * (edges[k] + edges[k + 1])), dtype=np.float64)
            if image.ndim != 3 or image.shape[0] != rows:
                raise SolasError(
                    f"a moving scene's image at t = {edges[k]:g} s has shape {image.shape}; it must be "
                    f"(H, W, 3) with H = {rows} rows at every time"
                )
            share = shares[k][:, None, None]
            total = image * share if total is None else total + image * share
        return total


def slice_shares(starts, ends, edges, exposure_s: float, source: PWMSource | None = None) -> np.ndarray:
    """(K, rows): the share of each row's exposure (its window [starts[r], ends[r]]) that lies in each slice
    [edges[k], edges[k + 1]] of the frame's time: the overlap's length over `exposure_s`, or the time `source`
    is on within the overlap (the light a PWM-driven source gives the row from that slice)."""
    low = np.maximum(np.asarray(starts)[None, :], np.asarray(edges)[:-1, None])
    high = np.maximum(np.minimum(np.asarray(ends)[None, :], np.asarray(edges)[1:, None]), low)
    return (high - low if source is None else source.on_time(low, high)) / exposure_s


def exposed_irradiance(shutter: Shutter | None, scene, exposure_s: float) -> np.ndarray:
    """The irradiance image (H, W, 3) each row sees on average over its window: a static image unchanged, a
    `FlickeringScene` exactly, a callable sampled (`Shutter.mean_over_windows`); no shutter is a global one."""
    if isinstance(scene, np.ndarray) or not (callable(scene) or isinstance(scene, FlickeringScene)):
        return scene
    shutter = shutter or Shutter()
    if isinstance(scene, FlickeringScene):
        return scene.mean_over(*shutter.windows(scene.static.shape[0], exposure_s))
    return shutter.mean_over_windows(scene, scene(0.0).shape[0], exposure_s)


@dataclass(frozen=True)
class PWMSource:
    """A light driven by pulse-width modulation: `frequency_hz`, `duty_cycle` (its on share of each period)
    and `phase` (where in the period it turns on, a fraction of the period)."""

    frequency_hz: float
    duty_cycle: float
    phase: float = 0.0

    def __post_init__(self):
        check_number(
            self.frequency_hz, "frequency_hz", 0.0, 1e9, "the PWM frequency in Hz", open_low=True, where="PWM source"
        )
        check_number(
            self.duty_cycle, "duty_cycle", 0.0, 1.0, "the on share of each period", open_low=True, where="PWM source"
        )
        check_number(
            self.phase,
            "phase",
            0.0,
            1.0,
            "where in the period it turns on, a fraction of the period",
            open_high=True,
            where="PWM source",
        )

    @property
    def period_s(self) -> float:
        return 1.0 / self.frequency_hz

    def _on_since_zero(self, t: np.ndarray) -> np.ndarray:
        """The on-time (s) over [0, t] of a source on over [0, DT) of each period."""
        period = self.period_s
        return np.floor(t / period) * self.duty_cycle * period + np.minimum(np.mod(t, period), self.duty_cycle * period)

    def on_time(self, starts, ends) -> np.ndarray:
        """The time (s) it is on within each window [start, end]."""
        shift = self.phase * self.period_s
        return self._on_since_zero(np.asarray(ends) - shift) - self._on_since_zero(np.asarray(starts) - shift)

    def visible_probability(self, window_s: float, least_on_s: float = 0.0) -> float:
        """The probability over a uniformly random phase that a window of `window_s` sees it on for at least
        `least_on_s` (at most the on-time and the window; module docstring)."""
        on = self.duty_cycle * self.period_s
        if not 0.0 <= least_on_s <= min(on, window_s):
            raise SolasError(
                f"least_on_s = {least_on_s!r} must be from 0 to the on-time {on:g} s and the window {window_s:g} s"
            )
        return min(1.0, (on + window_s - 2.0 * least_on_s) / self.period_s)


@dataclass(frozen=True)
class FlickeringScene:
    """A scene of a static irradiance image (H, W, 3) plus `light` (H, W, 3; W/m² while on) driven by
    `source`: e.g. an LED traffic light's pixels."""

    static: np.ndarray
    light: np.ndarray
    source: PWMSource

    def __post_init__(self):
        if np.shape(self.static) != np.shape(self.light) or np.ndim(self.static) != 3:
            raise SolasError(
                f"a flickering scene's static image {np.shape(self.static)} and light "
                f"{np.shape(self.light)} must be (H, W, 3) images of one shape"
            )

    def mean_over(self, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """Each row's average irradiance over its window [starts[r], ends[r]]."""
        share = self.source.on_time(starts, ends) / (ends - starts)
        return self.static + self.light * share[:, None, None]


def flickering_box(image: np.ndarray, box: tuple[int, int, int, int], source: PWMSource) -> FlickeringScene:
    """A scene whose pixels in `box` are the light of `source` (their irradiance while on) and the rest static."""
    x0, y0, x1, y1 = box
    if x1 > image.shape[1] or y1 > image.shape[0]:
        raise SolasError(f"--flicker box {box} reaches past the image's {image.shape[1]} x {image.shape[0]} pixels")
    static, light = image.copy(), np.zeros_like(image)
    light[y0:y1, x0:x1] = image[y0:y1, x0:x1]
    static[y0:y1, x0:x1] = 0.0
    return FlickeringScene(static, light, source)


def moving_image(image: np.ndarray, velocity_px_s: tuple[float, float]):
    """The scene ``scene(t)`` of an image moving at (vx, vy) pixels per second (right and down), e.g. a camera
    panning across a distant scene: the image shifted by (vx t, vy t), interpolated linearly between pixels,
    its edge pixels held past its borders."""
    from scipy.ndimage import shift

    vx, vy = velocity_px_s
    return lambda t: shift(image, (vy * t, vx * t, 0.0), order=1, mode="nearest")


@dataclass(frozen=True)
class SceneInTime:
    """A still image made a scene in time, as the `camera` command's and a batch's camera's options give it:
    the pixels of `box` (x0, y0, x1, y1: columns x0 to x1 − 1, rows y0 to y1 − 1) lit by `source`
    (`flickering_box`), or the whole image moving at `motion_px_s` (`moving_image`); one or the other."""

    box: tuple[int, int, int, int] | None = None
    source: PWMSource | None = None
    motion_px_s: tuple[float, float] | None = None

    def __post_init__(self):
        if (self.box is None) != (self.source is None) or (self.box is None) == (self.motion_px_s is None):
            raise SolasError(
                "a scene in time is a box of PWM-driven light (box and source) or the image's motion "
                "(motion_px_s), one of them"
            )

    def of(self, image: np.ndarray):
        """The scene of an (H, W, 3) irradiance image: a `FlickeringScene` or a callable of time."""
        if self.box is not None:
            return flickering_box(image, self.box, self.source)
        return moving_image(image, self.motion_px_s)

    def describe(self) -> dict:
        """For the RAW's metadata: ``flicker`` (the box and the source's values) or ``image_motion_px_s``."""
        if self.box is not None:
            return {"flicker": {"box": list(self.box), **asdict(self.source)}}
        return {"image_motion_px_s": list(self.motion_px_s)}
