"""`GridSpec`: every option of a PSF grid as one frozen, validated value, defined once: `psf_grid`
takes it, the command line builds it (`GridSpec.add_flags` / `GridSpec.from_args`: one flag per field,
declared with it by `options.option`, so adding an option is one edit here), the batch's grid cache
hashes its canonical form with the lens's hash and records it beside the grid.

Conventions: grid (rows, columns) of nodes (the command line's "COLSxROWS" text is converted by
`options.parse_wxh`); wavelengths in nm (None: the lens file's); field range in degrees as half
ranges (x, y) (None: the lens's field in both); sensor size (width, height) in mm; pitch in µm;
size in pixels.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass
from numbers import Real
from typing import Any

from ..errors import SolasError
from ..options import OptionSpec, floats, option, parse_size_mm, parse_wxh, wxh_text
from .base import DEFAULT_PITCH_UM, DEFAULT_SIZE, NORMALIZATIONS, WINDOW_ENERGY_LIMIT, check_grid, check_normalization
from .registry import DEFAULT_METHOD, METHODS, PUPIL_SAMPLES, RAYS, check_method, method_options

FIELD_SAMPLINGS = ("centers", "edges")
LAYOUTS = ("field", "sensor")  # nodes on field angles (tangents), or on sensor positions (`psf.sensor`)
# the options of one PSF, which the single-PSF command `psf` takes too
PSF_OPTIONS = ("pitch_um", "size", "method", "pupil_samples", "rays", "normalization", "auto_window")


RANGE_FORM = "X,Y in degrees, or one value for both"  # what --field-range-deg takes: its help and its message


def _range(text: str) -> tuple[float, float]:
    values = floats(text, "--field-range-deg")
    if len(values) not in (1, 2):
        raise SolasError(f"--field-range-deg {text!r} must be {RANGE_FORM}")
    return values[0], values[-1]


@dataclass(frozen=True)
class GridSpec(OptionSpec):
    """What a PSF grid is: its nodes, wavelengths, sampling and method, checked when built.

    `psf_grid` takes it; ``solas-mi psf-grid`` makes one flag of each field (its help: the field's
    meaning as the command line gives it) and builds it from them; a batch's grid cache keys on it.

    Parameters
    ----------
    grid : (int, int), default (8, 8)
        Nodes, (rows, columns).
    wavelengths_nm : tuple of float, optional
        The wavelengths (nm); default: the lens file's.
    layout : str, default "field"
        One of `LAYOUTS`: "field", nodes on field angles; "sensor", nodes on sensor positions (wide and
        fisheye lenses, `psf.sensor`).
    field_range_deg : (float, float), optional
        The half ranges (x, y) in degrees the "field" layout spans; default: the lens's field in both.
    field_sampling : str, default "centers"
        One of `FIELD_SAMPLINGS`: nodes at the centres of equal cells, or spanning the range's ends.
    sensor_mm : (float, float), optional
        The sensor (width, height) in mm of the "sensor" layout; default: the square in the image circle.
    pitch_um : float, default 0.5
        The PSFs' pixel pitch on the image plane (µm).
    size : int, default 160
        Pixels per side of each PSF.
    method : str, default "fraunhofer"
        A name of `registry.METHODS`.
    pupil_samples : int, default 128
        "fraunhofer": the N×N pupil grid.
    rays : int, default 512
        "geometric", "render": rays × rays per PSF.
    normalization : str, default "sum"
        One of `base.NORMALIZATIONS`.
    auto_window : bool, default False
        Double `size` until every window holds `base.WINDOW_ENERGY_LIMIT` of its light.
    distances_m : tuple of float, optional
        Object distances (m; inf: infinity) of a grid over field and distance (`psf.depth`); default: the
        lens file's object distance only.

    Raises
    ------
    SolasError
        For a value out of its range, a choice not among its choices, or options of different layouts
        mixed (a field range with the sensor layout, a sensor size with the field layout).

    Examples
    --------
    >>> from solas_mi.psf import GridSpec
    >>> spec = GridSpec(grid=(4, 6), method="geometric", rays=128)
    >>> spec.grid, spec.sampling_options()
    ((4, 6), {'pupil_samples': 128, 'rays': 128})
    """

    grid: tuple[int, int] = option(
        "COLSxROWS field nodes", (8, 8), parse=lambda t: parse_wxh(t, "--grid"), shown=wxh_text
    )
    wavelengths_nm: tuple[float, ...] | None = option(
        "nm, comma-separated (default: the lens file's)", parse=lambda t: tuple(floats(t, "--wavelengths-nm"))
    )
    layout: str = option(
        "field: nodes on field angles; sensor: nodes on sensor positions (wide and fisheye lenses)",
        LAYOUTS[0],
        choices=LAYOUTS,
    )
    field_range_deg: tuple[float, float] | None = option(
        f"half range: {RANGE_FORM} (default: the lens file's field)", parse=_range
    )
    field_sampling: str = option(
        "nodes at cell centres or spanning the range's ends", FIELD_SAMPLINGS[0], choices=FIELD_SAMPLINGS
    )
    sensor_mm: tuple[float, float] | None = option(
        "sensor WxH in mm for --layout sensor (default: the square in the image circle)",
        parse=lambda t: parse_size_mm(t, "--sensor-mm"),
    )
    pitch_um: float = option("image-plane pixel pitch (µm)", DEFAULT_PITCH_UM, parse=float)
    size: int = option("PSF width and height (pixels)", DEFAULT_SIZE, parse=int)
    method: str = option("PSF method", DEFAULT_METHOD, flag="--psf-method", choices=METHODS.names)
    pupil_samples: int = option(lambda: METHODS.option_help(PUPIL_SAMPLES.name), PUPIL_SAMPLES.default, parse=int)
    rays: int = option(lambda: METHODS.option_help(RAYS.name), RAYS.default, parse=int)
    normalization: str = option("PSF values", NORMALIZATIONS[0], flag="--normalize", choices=NORMALIZATIONS)
    auto_window: bool = option(
        f"double --size until each window holds {100 * WINDOW_ENERGY_LIMIT:g} %% of the light", False
    )
    distances_m: tuple[float, ...] | None = option(
        "object distances (m) of a grid over field and distance, comma-separated (inf: infinity), or N:NEAR for N "
        "nodes spaced evenly in 1/distance from infinity to NEAR (default: the lens file's object distance only)",
        parse=lambda t: parse_distances(t),
    )

    def __post_init__(self):
        set_ = object.__setattr__
        set_(self, "grid", _rows_cols(self.grid))
        set_(self, "wavelengths_nm", _wavelengths(self.wavelengths_nm))
        _choice(self.layout, LAYOUTS, "grid layout")
        _choice(self.field_sampling, FIELD_SAMPLINGS, "field sampling")
        if self.layout == "sensor" and self.field_range_deg is not None:
            raise SolasError(
                f"field range {self.field_range_deg!r} deg is for layout field; a sensor layout's "
                "nodes are set by its sensor size (sensor_mm)"
            )
        if self.layout == "field" and self.sensor_mm is not None:
            raise SolasError(f"sensor size {self.sensor_mm!r} mm is for layout sensor (nodes on sensor positions)")
        set_(self, "field_range_deg", _half_ranges(self.field_range_deg))
        if self.sensor_mm is not None:
            from .sensor import check_sensor_mm

            set_(self, "sensor_mm", check_sensor_mm(self.sensor_mm))
        check_grid(self.pitch_um, self.size)
        set_(self, "pitch_um", float(self.pitch_um))
        set_(self, "size", int(self.size))
        check_method(self.method)
        method_options(self.method, self.sampling_options())
        check_normalization(self.normalization)
        if not isinstance(self.auto_window, bool):
            raise SolasError(f"auto_window {self.auto_window!r} must be True or False")
        set_(self, "distances_m", check_distances(self.distances_m))

    def sampling_options(self) -> dict[str, Any]:
        """The PSF methods' own options.

        Returns
        -------
        dict
            ``{"pupil_samples": ..., "rays": ...}``; `registry.method_options` keeps those of `method`.
        """
        return {"pupil_samples": self.pupil_samples, "rays": self.rays}

    def canonical(self) -> dict:
        """The options that make the grid, as plain JSON values: equal grids, equal forms.

        Returns
        -------
        dict
            Field name → value, the options the layout and method do not use left out.
        """
        out = asdict(self)
        for name in ("field_range_deg", "field_sampling") if self.layout == "sensor" else ("sensor_mm",):
            del out[name]
        if self.distances_m is None:
            del out["distances_m"]  # the key of a grid at one distance stays what it was
        else:
            out["distances_m"] = [d if math.isfinite(d) else "inf" for d in self.distances_m]
        for name in set(self.sampling_options()) - set(method_options(self.method, self.sampling_options())):
            del out[name]
        return json.loads(json.dumps(out))

    def key(self, lens_hash: str) -> str:
        """What identifies the grid of a lens with these options.

        Parameters
        ----------
        lens_hash : str
            The lens's `Lens.hash`.

        Returns
        -------
        str
            16 hex digits: a hash of `lens_hash` and `canonical`.
        """
        text = json.dumps({"lens_hash": lens_hash, **self.canonical()}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def _rows_cols(value) -> tuple[int, int]:
    ok = (
        isinstance(value, (tuple, list))
        and len(value) == 2
        and all(isinstance(v, int) and not isinstance(v, bool) and v >= 1 for v in value)
    )
    if not ok:
        raise SolasError(
            f"grid {value!r} must be (rows, columns), each an integer >= 1 (the command line's "
            "--grid COLSxROWS is converted to it)"
        )
    return int(value[0]), int(value[1])


def _number(value, what: str) -> float:
    if not isinstance(value, Real) or isinstance(value, bool) or not math.isfinite(value):
        raise SolasError(f"{what} {value!r} must be a finite number")
    return float(value)


def _one_or_many(value, allowed: str, what: str):
    """One number as a sequence of one, or a sequence as given; SolasError (naming `what` and the
    `allowed` form) for text or anything else that is not iterable."""
    values = (value,) if isinstance(value, Real) else value
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        raise SolasError(f"{what} {value!r} must be {allowed}")
    return values


def _wavelengths(value) -> tuple[float, ...] | None:
    """None, one wavelength (nm) or a sequence of them; each a positive number (the lens checks its glasses)."""
    if value is None:
        return None
    out = tuple(
        _number(v, "wavelength (nm)")
        for v in _one_or_many(value, "a number or a sequence of numbers (nm)", "wavelengths")
    )
    if not out or min(out) <= 0:
        raise SolasError(f"wavelengths {value!r} must be one or more positive numbers (nm)")
    if len({f"{w:g}" for w in out}) != len(out):  # each names a channel of the grid file (psf_531nm)
        raise SolasError(f"wavelengths {value!r} must differ from each other (to 6 digits): each is a channel")
    return out


def inverse_spaced(count: int, near_m: float) -> tuple[float, ...]:
    """`count` object distances (m) spaced evenly in 1/distance, where defocus is linear, from infinity
    to `near_m`, far to near (one node: infinity)."""
    if not (isinstance(count, int) and count >= 1):
        raise SolasError(f"depth node count {count!r} must be a whole number >= 1")
    near = _number(near_m, "nearest distance (m)")
    if near <= 0:
        raise SolasError(f"nearest distance {near_m!r} m must be positive")
    return tuple(math.inf if k == 0 else near * (count - 1) / k for k in range(count))


def parse_distances(text: str) -> tuple[float, ...]:
    """--distances-m: "inf,40,20,10" (m, far to near) or "N:NEAR" (`inverse_spaced`)."""
    if ":" in text:
        count_text, _, near_text = text.partition(":")
        try:
            count, near = int(count_text), float(near_text)
        except ValueError:
            raise SolasError(
                f"--distances-m {text!r} must be N:NEAR (N nodes, NEAR in metres) or distances in m, comma-separated"
            ) from None
        return inverse_spaced(count, near)  # its own message for a count or distance out of range
    return tuple(floats(text, "--distances-m"))


def check_distances(value) -> tuple[float, ...] | None:
    """None, or object distances (m), positive (inf allowed), distinct, sorted far to near."""
    if value is None:
        return None
    out = []
    for v in _one_or_many(value, "a sequence of distances (m)", "distances"):
        if not isinstance(v, Real) or isinstance(v, bool) or math.isnan(v) or not float(v) > 0:
            raise SolasError(f"distance {v!r} m must be a positive number (inf: infinity)")
        out.append(float(v))
    if not out or len(set(out)) != len(out):
        raise SolasError(f"distances {value!r} m must be one or more distinct distances")
    return tuple(sorted(out, reverse=True))


def _half_ranges(value) -> tuple[float, float] | None:
    """None, or one half range (both axes) or (x, y), degrees, non-negative and below 89."""
    if value is None:
        return None
    from ..optics.fields import ANGLE

    hx, hy = ANGLE.check((value, value) if isinstance(value, Real) else value)
    if hx < 0 or hy < 0:
        raise SolasError(f"field range ({hx:g}, {hy:g}) deg must be non-negative (half ranges)")
    return hx, hy


def _choice(value, allowed: tuple[str, ...], what: str) -> None:
    if not isinstance(value, str) or value not in allowed:
        raise SolasError(f"{what} {value!r} must be one of {', '.join(allowed)}")
