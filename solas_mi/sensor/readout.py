"""`Readout`, a stage of the sensor's chain: a photodiode's charge over an exposure, read at a conversion gain
into an ADC (EMVA 1288's linear model, `emva`), and `read_charges`, the frames of a chain's readouts.

An HDR pixel reads several of these (`chain`): split pixels (a large and a small photodiode, the small one
seeing the share `sensitivity` of the large one's photo-electrons), dual conversion gain (one photodiode's
charge read twice, at a high and a low gain: readouts naming the same `photodiode` and `exposure_ratio`
share their charge, its shot and dark noise), multiple exposures (the share `exposure_ratio` of the frame's
exposure time, an independent charge).

Per charge, in this order: PRNU gain g of the photodiode (fixed pattern), Poisson(g s r μ_e) photo-electrons
and Poisson(i_d r t) dark electrons (s the sensitivity, r the exposure ratio, μ_e the pixel's mean
photo-electrons over the frame's exposure t); then per readout of the charge: at most its full well
(the well, or the floating diffusion at a high conversion gain), its DSNU offset (fixed pattern) and
Gaussian read noise, and its ADC y = round(K e + black) clipped to [0, 2^bits − 1].

Random streams: the first charge of a chain draws from the one-readout sensor's streams, its fixed
pattern from [seed, 0] and its temporal noise from [seed, 1, frame], so every sensor of one linear readout
gives the frames it gave before the chain; every other charge from its own named streams, [seed, 2, id]
and [seed, 3, id, frame] with id the CRC-32 of its name ("photodiode@exposure ratio"), so adding a readout
changes no other charge's draws.

The fixed pattern depends on the seed, the frame's shape and the photodiode's and readouts' spreads, never
on the frame: the patterns of the last frame's charges are kept (`held_pattern`, read-only arrays,
`PATTERN_VALUES_PER_READOUT`) and reused for the next frame of the same sensor and seed, as a batch draws them.
"""

from __future__ import annotations

import math
import threading
import zlib
from dataclasses import asdict, dataclass, fields

import numpy as np

from ..errors import SolasError
from ..threads import in_threads
from . import emva
from .limits import ADC_DEFAULTS, PRNU_MEANING, READOUT_DEFAULTS, check_adc, check_gain, check_number, check_ranged

SHARED = ("sensitivity", "dark_current_e_s", "prnu")  # properties of a photodiode: equal on the readouts of a charge


@dataclass(frozen=True)
class Readout:
    """One readout: its name, the photodiode it reads with that photodiode's `sensitivity` (its photo-electrons
    over the reference photodiode's, 1 for the large one) and the `exposure_ratio` of its exposure (over the
    frame's), the noise (e⁻), full well, conversion gain (DN/e⁻) and ADC. What is left out takes
    `limits.READOUT_DEFAULTS` and `limits.ADC_DEFAULTS`."""

    name: str = "linear"
    photodiode: str = "large"
    sensitivity: float = 1.0
    exposure_ratio: float = 1.0
    dark_current_e_s: float = READOUT_DEFAULTS["dark_current_e_s"]
    read_noise_e: float = READOUT_DEFAULTS["read_noise_e"]
    prnu: float = READOUT_DEFAULTS["prnu"]
    dsnu_e: float = READOUT_DEFAULTS["dsnu_e"]
    full_well_e: float = READOUT_DEFAULTS["full_well_e"]
    gain_dn_per_e: float = READOUT_DEFAULTS["gain_dn_per_e"]
    bit_depth: int = ADC_DEFAULTS["bit_depth"]
    black_level_dn: int = ADC_DEFAULTS["black_level_dn"]

    def __post_init__(self):
        where = f"sensor readout {self.name!r}:"
        for name in ("name", "photodiode"):
            value = getattr(self, name)
            if not isinstance(value, str) or not value.strip() or not value.isprintable():
                raise SolasError(f"{where} {name} = {value!r} must be a non-empty printable name")
        check_number(
            self.sensitivity,
            "sensitivity",
            0.0,
            1.0,
            "the photodiode's photo-electrons over the "
            "reference photodiode's: 1 for the large one of a split pixel, less for the small one",
            open_low=True,
            where=where,
        )
        check_number(
            self.exposure_ratio,
            "exposure_ratio",
            0.0,
            1.0,
            "the readout's exposure time over the frame's",
            open_low=True,
            where=where,
        )
        for name in ("dark_current_e_s", "read_noise_e", "dsnu_e", "full_well_e"):
            check_ranged(getattr(self, name), name, where=where)
        check_number(self.prnu, "prnu", 0.0, 1.0, PRNU_MEANING, open_high=True, where=where)
        check_adc(self.bit_depth, self.black_level_dn, where=where)
        check_gain(self.gain_dn_per_e, self.full_well_e, self.bit_depth, where=where)

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    def describe(self) -> dict:
        return asdict(self)

    @property
    def charge(self) -> str:
        """The name of the charge it reads: its photodiode over its exposure."""
        return f"{self.photodiode}@{self.exposure_ratio!r}"

    @property
    def response(self) -> float:
        """Its photo-electrons per photo-electron of the reference photodiode over the frame's exposure."""
        return self.sensitivity * self.exposure_ratio

    @property
    def white_level_dn(self) -> int:
        return 2**self.bit_depth - 1

    @property
    def saturation_dn(self) -> float:
        """y_sat: the signal above black (DN) at saturation, the well or the ADC, whichever fills first."""
        return emva.saturation_dn(self.gain_dn_per_e, self.full_well_e, self.white_level_dn, self.black_level_dn)

    def dark_mean_dn(self, exposure_s: float) -> float:
        """μ_y.dark = black + K i_d r t (DN) over the frame's exposure t."""
        return emva.dark_mean_dn(
            self.black_level_dn, self.gain_dn_per_e, self.dark_current_e_s, exposure_s * self.exposure_ratio
        )

    def dark_variance_e2(self, exposure_s: float) -> float:
        """σ_d² = σ_r² + i_d r t (e⁻²) over the frame's exposure t."""
        return emva.dark_variance_e2(self.read_noise_e, self.dark_current_e_s, exposure_s * self.exposure_ratio)


def check_charges(readouts: tuple[Readout, ...]) -> None:
    """The readouts of one charge agree on its photodiode's properties (`SHARED`)."""
    first = {}
    for r in readouts:
        other = first.setdefault(r.charge, r)
        for name in SHARED:
            if getattr(r, name) != getattr(other, name):
                raise SolasError(
                    f"sensor readout {r.name!r}: {name} = {getattr(r, name)!r} differs from the "
                    f"{getattr(other, name)!r} of readout {other.name!r}; both read photodiode {r.photodiode!r} "
                    "over the same exposure (one charge), whose property it is"
                )


def charge_pattern(readouts: list[Readout], shape: tuple[int, int], rng: np.random.Generator):
    """The fixed pattern of one charge from its stream: the photodiode's per-pixel gain (mean 1, spread `prnu`)
    and each readout's per-pixel offset (e⁻, mean 0, spread `dsnu_e`)."""
    gain = rng.standard_normal(shape)
    gain *= readouts[0].prnu
    gain += 1.0
    offsets = []
    for r in readouts:
        offsets.append(rng.standard_normal(shape))
        offsets[-1] *= r.dsnu_e
    return np.clip(gain, 0.0, None, out=gain), offsets


# the fixed patterns held between frames, per pixel and readout at most: its offset and, for the first readout
# of a charge, the charge's gain (float64 values; the camera's and batch's memory estimates count them,
# `sensor.commands.frame_bytes`)
PATTERN_VALUES_PER_READOUT = 2
BAND_VALUES = 1 << 15  # the values of a band of a frame worked at once (`bands`: 256 KiB of float64)
_PATTERNS: dict[tuple, tuple[np.ndarray, list[np.ndarray]]] = {}
_PATTERNS_LOCK = threading.Lock()  # frames captured on threads at once (a threaded Dask worker)


def held_pattern(readouts: list[Readout], shape: tuple[int, int], charge: tuple, rng, held: set):
    """`charge_pattern` of one charge (`charge`: the seed, its index and name), drawn from its stream `rng` the
    first time and kept while a frame of the same shape asks for it again (module docstring); read-only
    arrays. Its key is added to `held`, the keys the frame keeps."""
    key = (*charge, shape, readouts[0].prnu, tuple(r.dsnu_e for r in readouts))
    held.add(key)
    with _PATTERNS_LOCK:
        pattern = _PATTERNS.get(key)
    if pattern is None:
        pattern = charge_pattern(readouts, shape, rng)
        for array in (pattern[0], *pattern[1]):
            array.flags.writeable = False
        with _PATTERNS_LOCK:
            _PATTERNS[key] = pattern
    return pattern


def charge_streams(index: int, charge: str, seed: int, frame: int):
    """The fixed-pattern and temporal random streams of the `index`-th charge of a chain (module docstring)."""
    if index == 0:
        return np.random.default_rng([seed, 0]), np.random.default_rng([seed, 1, frame])
    key = zlib.crc32(charge.encode())
    return np.random.default_rng([seed, 2, key]), np.random.default_rng([seed, 3, key, frame])


def bands(shape: tuple[int, ...]):
    """The row slices of a frame of `shape` in bands of about `BAND_VALUES` values (at least a row each)."""
    rows = max(1, BAND_VALUES // max(1, math.prod(shape[1:])))
    return [slice(start, start + rows) for start in range(0, shape[0], rows)]


def read_out(readout: Readout, electrons: np.ndarray, offset: np.ndarray, temporal: np.random.Generator) -> np.ndarray:
    """The frame (uint16 DN) a readout gives for a charge's `electrons`: at most its full well, its `offset`
    and read noise (drawn from `temporal`, row after row), its ADC. Done in bands of `BAND_VALUES` values,
    which stay in the processor's cache: the same draws and the same arithmetic as on the whole frame."""
    frame = np.empty(electrons.shape, dtype=np.uint16)
    for band in bands(electrons.shape):
        read = np.minimum(electrons[band], readout.full_well_e)
        noise = temporal.standard_normal(read.shape)
        noise *= readout.read_noise_e
        noise += offset[band]
        read += noise
        read *= readout.gain_dn_per_e  # the ADC, in place: round(K e + black), clipped
        read += readout.black_level_dn
        frame[band] = np.clip(np.rint(read, out=read), 0, readout.white_level_dn, out=read)
    return frame


def charge_electrons(group: list[Readout], gain, mu_e, exposure_s: float, temporal, draw: tuple, defects):
    """The electrons (float64) of one charge read by the readouts `group`: Poisson photo-electrons of mean
    `gain` (its pattern's) × `mu_e` × the photodiode's response, then Poisson dark electrons, drawn from
    `temporal`; dead pixels emptied, hot ones filled (`defects`, drawn by `draw`: seed, frame and the charge's
    index)."""
    first = group[0]
    # past the full well the count is clipped anyway: capping the Poisson means at 2 × full well + 1000 keeps
    # them within NumPy's Poisson range (the Chernoff bound puts the chance that the well then fails to fill
    # below e⁻⁷⁰⁰)
    cap = 2.0 * max(r.full_well_e for r in group) + 1000.0
    mean = np.multiply(gain, mu_e if first.response == 1.0 else mu_e * first.response)  # (x × 1.0 is x: skipped)
    electrons = temporal.poisson(np.minimum(mean, cap, out=mean)).astype(np.float64)
    if defects is not None:
        electrons[defects[1]] = 0.0  # dead: no photo-electrons
    seconds = exposure_s * first.exposure_ratio
    electrons += temporal.poisson(min(first.dark_current_e_s * seconds, cap), electrons.shape)
    if defects is not None:
        stage, _, hot = defects
        electrons[hot] += stage.hot_electrons(hot, seconds, cap, *draw)
    return electrons


def read_charges(
    readouts: tuple[Readout, ...], mu_e: np.ndarray, exposure_s: float, seed: int, frame: int, defects=None
) -> list[np.ndarray]:
    """The frame (H, W, uint16 DN) of each readout, in order, for the pixels' mean photo-electrons `mu_e` of
    the reference photodiode over the frame's exposure `exposure_s` (module docstring); `defects`: the
    sensor's `defects.Defects` with its dead and hot pixels (None: none). A dead pixel's photo-electrons are
    dropped after they are drawn, so that the other pixels' draws stay as they were. The charges, each
    from its own streams, are drawn on the process's threads at once (`threads.in_threads`)."""
    charges: dict[str, list[int]] = {}
    for i, r in enumerate(readouts):
        charges.setdefault(r.charge, []).append(i)
    frames: list[np.ndarray | None] = [None] * len(readouts)
    held: set[tuple] = set()

    def read(charge: tuple[int, tuple[str, list[int]]]) -> None:
        index, (name, members) = charge
        group = [readouts[i] for i in members]
        fixed, temporal = charge_streams(index, name, seed, frame)
        gain, offsets = held_pattern(group, mu_e.shape, (seed, index, name), fixed, held)
        electrons = charge_electrons(group, gain, mu_e, exposure_s, temporal, (seed, frame, index), defects)
        for i, offset in zip(members, offsets):
            frames[i] = read_out(readouts[i], electrons, offset, temporal)

    in_threads(read, list(enumerate(charges.items())))
    with _PATTERNS_LOCK:
        for key in set(_PATTERNS) - held:
            del _PATTERNS[key]  # another sensor's, seed's or frame size's: not held
    return frames
