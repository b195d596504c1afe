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
    """How the rows take their windows of the frame's exposure (a stage of the sensor's chain, its
    ``[sensor.shutter]`` table; module docstring).

    Parameters
    ----------
    mode : str, default "global"
        One of `MODES`: every row over [0, t] (global), or row r over [r L, r L + t] (rolling).
    line_time_s : float, default 0
        A rolling shutter's time between two rows' starts L (s, above 0); 0 for a global one.
    direction : str, default "top-down"
        One of `DIRECTIONS`: the row read first, row 0 (top-down) or the last (bottom-up).
    time_samples : int, default 64
        The slices of the frame's span over which a moving scene or camera is sampled (1 to 100 000).

    Raises
    ------
    SolasError
        For a mode or direction not listed, a line time that does not go with the mode, or a bad count.

    Examples
    --------
    >>> from solas_mi.sensor import Shutter
    >>> starts, ends = Shutter("rolling", 30e-6).windows(3, 1e-3)
    >>> [round(float(t) * 1e6) for t in starts], [round(float(t) * 1e6) for t in ends]
    ([0, 30, 60], [1000, 1030, 1060])
    """

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
        """Its fields, for metadata.

        Returns
        -------
        dict
            Mode, line time, direction and time samples by name.
        """
        return asdict(self)

    def windows(self, rows: int, exposure_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Each row's window of the frame.

        Parameters
        ----------
        rows : int
            The frame's rows.
        exposure_s : float
            The exposure time t (s).

        Returns
        -------
        tuple of numpy.ndarray
            Each row's start and end (s, from the first row's start), in the order of the rows.
        """
        order = np.arange(rows, dtype=np.float64)
        if self.direction == "bottom-up":
            order = order[::-1]
        starts = order * self.line_time_s
        return starts, starts + exposure_s

    def slices(self, rows: int, exposure_s: float) -> np.ndarray:
        """The slices of the frame's span of time over which a moving scene is sampled.

        Parameters
        ----------
        rows : int
            The frame's rows.
        exposure_s : float
            The exposure time t (s).

        Returns
        -------
        numpy.ndarray
            The edges (s) of `time_samples` even slices from the first row's start to the last row's end.
        """
        starts, ends = self.windows(rows, exposure_s)
        return np.linspace(starts.min(), ends.max(), self.time_samples + 1)

    def mean_over_windows(self, scene, rows: int, exposure_s: float) -> np.ndarray:
        """The irradiance each row of a moving scene averages over its window (module docstring).

        Parameters
        ----------
        scene : callable
            ``scene(t)``: the (H, W, 3) irradiance image (W/m²) at time t (s, from the first row's start).
        rows : int
            The frame's rows H.
        exposure_s : float
            The exposure time t (s).

        Returns
        -------
        numpy.ndarray
            (H, W, 3): each row's mean over its window, from `time_samples` instants.

        Raises
        ------
        SolasError
            For a scene whose image is not (H, W, 3) with H = `rows` at every instant.
        """
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
        assert total is not None  # time_samples ≥ 1
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
    """A light driven by pulse-width modulation: on over [φT, φT + DT) of each period T (module docstring).

    Parameters
    ----------
    frequency_hz : float
        The PWM frequency 1/T (Hz, above 0, at most 10⁹).
    duty_cycle : float
        Its on share D of each period (above 0, at most 1).
    phase : float, default 0
        Where in the period it turns on, φ, a fraction of the period (0 to below 1).

    Raises
    ------
    SolasError
        For a value out of its range.

    Examples
    --------
    >>> from solas_mi.sensor import PWMSource
    >>> led = PWMSource(100.0, 0.1, phase=0.5)  # on from 5 ms to 6 ms of each 10 ms
    >>> [round(float(t) * 1e3, 6) for t in led.on_time([0.0, 0.0045], [0.001, 0.0055])]
    [0.0, 0.5]
    >>> round(led.visible_probability(1e-3), 6)  # (DT + w) / T over random phases
    0.2
    """

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
        """The period T = 1 / frequency (s)."""
        return 1.0 / self.frequency_hz

    def _on_since_zero(self, t: np.ndarray) -> np.ndarray:
        """The on-time (s) over [0, t] of a source on over [0, DT) of each period."""
        period = self.period_s
        return np.floor(t / period) * self.duty_cycle * period + np.minimum(np.mod(t, period), self.duty_cycle * period)

    def on_time(self, starts, ends) -> np.ndarray:
        """The time it is on within each window [start, end], in closed form.

        Parameters
        ----------
        starts, ends : array_like
            The windows' starts and ends (s, on the same clock as the phase: 0 at a period's start).

        Returns
        -------
        numpy.ndarray
            The on-time (s) of each window.
        """
        shift = self.phase * self.period_s
        return self._on_since_zero(np.asarray(ends) - shift) - self._on_since_zero(np.asarray(starts) - shift)

    def visible_probability(self, window_s: float, least_on_s: float = 0.0) -> float:
        """The probability over a uniformly random phase that a window sees it on long enough (module docstring).

        Parameters
        ----------
        window_s : float
            The window's length w (s): the exposure under a global shutter.
        least_on_s : float, default 0
            The on-time τ the window needs to see it (s; at most the on-time and the window).

        Returns
        -------
        float
            min(1, (DT + w − 2τ)/T).

        Raises
        ------
        SolasError
            For a `least_on_s` out of its range.
        """
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
        if self.box is not None and self.source is not None:
            return flickering_box(image, self.box, self.source)
        assert self.motion_px_s is not None  # one or the other (__post_init__)
        return moving_image(image, self.motion_px_s)

    def describe(self) -> dict:
        """For the RAW's metadata: ``flicker`` (the box and the source's values) or ``image_motion_px_s``."""
        if self.box is not None and self.source is not None:
            return {"flicker": {"box": list(self.box), **asdict(self.source)}}
        assert self.motion_px_s is not None  # one or the other (__post_init__)
        return {"image_motion_px_s": list(self.motion_px_s)}
