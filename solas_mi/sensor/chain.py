"""`SensorChain`: a sensor as an ordered list of stages, `STAGES` (a `solas_mi.registry.Registry`): the photon
conversion, defect pixels, one or more readouts, the merge of an HDR sensor's readouts into one linear
signal and the compander that squeezes it into the output's bits. Each stage checks its own values, draws
from its own named random streams (`readout`, `defects`) and has its inverse in the image processor
(`SensorChain.linear_dn`, `defective_pixels`).

A flat `[sensor]` table (`model.SensorModel`) is the chain photons → one readout (`chain_of`), and gives the
frames it gave before the chain, bit for bit. A TOML file names the stages after the photon conversion's
fields in `[sensor]`: `[[sensor.readout]]` tables, one per readout in order of falling response, then
`[sensor.shutter]`, `[sensor.merge]`, `[sensor.compander]`, `[sensor.defects]` (`STAGES`' keys;
docs/details/sensor.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from ..errors import SolasError
from ..registry import Registry
from . import emva
from .compander import Compander
from .defects import Defects
from .merge import Merge
from .model import SensorModel
from .photons import PhotonConversion
from .qe import QECurve
from .readout import Readout, check_charges, read_charges
from .timing import Shutter, exposed_irradiance

# in the order of the chain; each entry's `field`: the SensorChain field that holds it (`many`: a tuple of them),
# `keys`: its TOML table's keys (the docs' table shows them)
STAGES = Registry("sensor stage", shown=("keys",))


def _stage(name: str, cls, **extra) -> None:
    STAGES.register(name, cls, keys=tuple(f.name for f in fields(cls)), **extra)


_stage("photons", PhotonConversion, field="photons", many=False, reference="EMVA 1288 release 4.0, eqs. 1-2",
       summary="irradiance → mean photo-electrons: pixel pitch, colour filter array, quantum efficiencies (the "
       "[sensor] table's own keys)")
_stage("shutter", Shutter, field="shutter", many=False,
       summary="the rows' windows of the exposure in time: global, or rolling with a line time; what a moving or "
       "PWM-flickering scene gives each row (module timing)")
_stage("defects", Defects, field="defects", many=False,
       summary="defect pixels fixed per sensor: dead ones, which collect no light, and hot ones, with more dark current")
_stage("readout", Readout, field="readouts", many=True, reference="EMVA 1288 release 4.0, section 2",
       summary="a photodiode's charge over an exposure read at a conversion gain into an ADC: shot, dark and read "
       "noise, PRNU, DSNU, full well ([[sensor.readout]] tables, one per readout)")
_stage("merge", Merge, field="merge", many=False,
       summary="the readouts' estimates, each below a threshold of its saturation, as one linear signal of 16-24 bits")
_stage("compander", Compander, field="compander", many=False,
       summary="piecewise-linear companding of the merged signal through knee points to the output's bits; "
       "decompanded by the image processor")
HEAD = STAGES.names()[0]  # the stage whose fields the [sensor] table itself holds


@dataclass(frozen=True)
class SensorChain:
    """A sensor as its chain of stages ([the sensor](../details/sensor.md)), checked when built.

    Parameters
    ----------
    photons : PhotonConversion
        The photon conversion: pixel pitch, colour filter array, quantum efficiencies.
    readouts : tuple of Readout
        The readouts, in order of falling response (DN per reference photo-electron).
    merge : Merge, optional
        The merge of two or more readouts into one linear signal; none with one readout.
    compander : Compander, optional
        The companding of the merged signal to the output's bits.
    defects : Defects, optional
        Dead and hot pixels.
    shutter : timing.Shutter, optional
        Global or rolling; none is a global one.

    Raises
    ------
    SolasError
        For a stage of the wrong type, readouts of one name, readouts of one charge that disagree on its
        photodiode, readouts out of order, a merge missing or too narrow, a compander that does not end at
        the merged signal's white level.
    """
    photons: PhotonConversion
    readouts: tuple[Readout, ...]
    merge: Merge | None = None
    compander: Compander | None = None
    defects: Defects | None = None
    shutter: Shutter | None = None

    def __post_init__(self):
        object.__setattr__(self, "readouts", tuple(self.readouts))
        for kind, entry in STAGES.items():
            value = getattr(self, entry.extra["field"])
            if not all(stage is None or isinstance(stage, entry.function) for stage in (value if entry.extra["many"]
                                                                                       else (value,))):
                raise SolasError(f"sensor {kind} must be a {entry.function.__name__}")
        if not self.readouts or self.photons is None:
            raise SolasError("a sensor's chain needs its photon conversion and at least one readout")
        names = [r.name for r in self.readouts]
        if len(set(names)) != len(names):
            raise SolasError(f"sensor readout names {names} must differ (each names its own stream and frame)")
        check_charges(self.readouts)
        if (len(self.readouts) > 1) != (self.merge is not None):
            raise SolasError(f"a sensor of {len(self.readouts)} readout(s) takes "
                             f"{'a [sensor.merge] table' if len(self.readouts) > 1 else 'no merge'}: the merge "
                             "makes one signal of two or more readouts")
        if self.merge is not None:
            self.merge.check_readouts(self.readouts)
        if self.compander is not None and (self.merge is None or self.compander.top != self.merge.white_level_dn):
            raise SolasError(f"sensor compander's last knee must sit at the merged signal's white level "
                             f"({self.merge.white_level_dn if self.merge else 'no merge: a compander follows one'}), "
                             f"not {self.compander.top}")

    @classmethod
    def from_dict(cls, values: dict) -> SensorChain:
        """A chain from a ``[sensor]`` table naming its stages (module docstring).

        Parameters
        ----------
        values : dict
            The table: the photon conversion's fields, ``readout`` (a list of tables), ``merge`` and
            ``compander`` (tables).

        Returns
        -------
        SensorChain
            The chain, checked.

        Raises
        ------
        SolasError
            For an unknown name, a stage's table of the wrong shape, or a bad value.
        """
        values = dict(values)
        tables = {kind: values.pop(kind, None) for kind in STAGES if kind != HEAD}
        readouts = tables.pop("readout")
        if readouts is None:  # a flat sensor's table (one readout) with stages of its own, e.g. defects
            flat = chain_of(SensorModel.from_dict(values))
            stages: dict[str, Any] = {"photons": flat.photons, "readouts": flat.readouts}
        elif not isinstance(readouts, list) or not all(isinstance(r, dict) for r in readouts):
            raise SolasError("sensor readout must be [[sensor.readout]] tables, one per readout")
        else:
            stages = {"photons": _photons(values), "readouts": tuple(_made("readout", r) for r in readouts)}
        for kind, table in tables.items():  # the stages of one table each
            stages[STAGES[kind].extra["field"]] = None if table is None else _made(kind, table)
        return cls(**stages)

    def stages(self) -> list[tuple[str, Any]]:
        """The stages in the order of the chain.

        Returns
        -------
        list of (str, object)
            (kind in `STAGES`, stage) pairs.
        """
        out = []
        for kind, entry in STAGES.items():
            value = getattr(self, entry.extra["field"])
            out += [(kind, stage) for stage in (value if entry.extra["many"] else (value,)) if stage is not None]
        return out

    def describe(self) -> dict:
        """Every stage's values, in order: the RAW's metadata.

        Returns
        -------
        dict
            ``{"stages": [...]}``, each stage's kind (``stage``) and values, JSON-ready.
        """
        return {"stages": [{"stage": kind, **stage.describe()} for kind, stage in self.stages()]}

    def readout_frames(self, irradiance: np.ndarray, exposure_s: float, seed: int, frame: int) -> list[np.ndarray]:
        """Each readout's frame of an irradiance image, before any merge.

        Parameters
        ----------
        irradiance : numpy.ndarray, callable or timing.FlickeringScene
            (H, W, 3) image-plane irradiance (W/m²), or a scene in time (`timing`: each row's window of it).
        exposure_s : float
            The frame's exposure time (s); a readout takes its `Readout.exposure_ratio` of it.
        seed : int
            The sensor's seed: its fixed pattern.
        frame : int
            The frame's number: its temporal noise.

        Returns
        -------
        list of numpy.ndarray
            (H, W) uint16 DN per readout, in the chain's order.
        """
        mu_e = self.photons.mean_electrons(exposed_irradiance(self.shutter, irradiance, exposure_s), exposure_s)
        if self.defects is None:
            return read_charges(self.readouts, mu_e, exposure_s, seed, frame)
        return read_charges(self.readouts, mu_e, exposure_s, seed, frame,
                            (self.defects, *self.defects.pixel_map(mu_e.shape, seed)))

    def output(self, frames: list[np.ndarray]) -> np.ndarray:
        """The sensor's RAW of its readouts' frames.

        Parameters
        ----------
        frames : list of numpy.ndarray
            Each readout's frame (`readout_frames`).

        Returns
        -------
        numpy.ndarray
            The one readout's frame, or the merged signal (uint32), or its companded codes (uint16).
        """
        if self.merge is None:
            return frames[0]
        merged = self.merge.merge(self.readouts, frames)
        return merged if self.compander is None else self.compander.compand(merged)

    def predicted_snr(self, electrons: float, exposure_s: float) -> float:
        """The SNR of the sensor's linear signal (decompanded) in closed form, for a flat field.

        The readout in use's EMVA 1288 SNR (`Merge.predicted_snr`; eq. 15 with one readout), with the
        compander's rounding added as the variance Δ²/12 of its segment's step Δ (merged DN), which holds
        where the signal's noise spans a step or more.

        Parameters
        ----------
        electrons : float
            The reference photodiode's mean photo-electrons over the frame's exposure.
        exposure_s : float
            The frame's exposure time (s).

        Returns
        -------
        float
            The SNR (a ratio, not dB).
        """
        first = self.readouts[0]
        if self.merge is None:
            return emva.snr(electrons, first.gain_dn_per_e, first.dark_variance_e2(exposure_s))
        snr = self.merge.predicted_snr(self.readouts, electrons, exposure_s)
        if self.compander is None:
            return snr
        signal = electrons * first.gain_dn_per_e * first.response  # merged DN
        step = float(self.compander.step(np.array([signal]))[0])
        return signal / math.sqrt((signal / snr) ** 2 + step**2 / 12.0)

    def defective_pixels(self, shape: tuple[int, int], seed: int) -> np.ndarray | None:
        """The defect map of sensor `seed` (its dead and hot pixels), as a camera's calibration stores it.

        Parameters
        ----------
        shape : tuple of int
            Rows and columns of the frame.
        seed : int
            Which sensor of this model (its fixed pattern and defects).

        Returns
        -------
        numpy.ndarray or None
            True at a defect pixel (`defects.Defects.pixel_map`: dead or hot); None without defects.
        """
        if self.defects is None:
            return None
        dead, hot = self.defects.pixel_map(shape, seed)
        return dead | hot

    def dynamic_range_db(self, exposure_s: float) -> float:
        """EMVA 1288's dynamic range, 20 log10(μ_e.sat / μ_e.min), of the reference photodiode's electrons.

        μ_e.sat: where the last readout saturates (`saturation_e`); μ_e.min: the signal of SNR = 1 of the
        first readout (`emva.threshold_electrons`; its merged estimates are codes already: no rounding).

        Parameters
        ----------
        exposure_s : float
            The frame's exposure time (s): the dark current's share of the noise floor.

        Returns
        -------
        float
            The dynamic range (dB).
        """
        first = self.readouts[0]
        floor = emva.threshold_electrons(first.gain_dn_per_e, first.dark_variance_e2(exposure_s))
        return 20.0 * math.log10(self.saturation_e * first.response / floor)

    # what the image processor and the commands read of a sensor (as of `SensorModel`)
    @property
    def cfa(self) -> str:
        """The colour filter array's pattern."""
        return self.photons.cfa

    @property
    def channel_wavelengths_nm(self) -> tuple[float, float, float]:
        """The wavelength (nm) that stands for each image channel R, G, B."""
        return self.photons.channel_wavelengths_nm

    def effective_qe(self) -> np.ndarray:
        """Q[f, c] (4 × 3): the electrons per photon of channel c on a pixel of filter f.

        Returns
        -------
        numpy.ndarray
            `PhotonConversion.effective_qe`.
        """
        return self.photons.effective_qe()

    @property
    def bit_depth(self) -> int:
        """The RAW's bits: the readout's, the merged signal's or the compander's."""
        return self.compander.bit_depth if self.compander else self.merge.bits if self.merge else self.readouts[0].bit_depth

    @property
    def black_level_dn(self) -> int:
        """The black level of the linear signal: the readout's, or the merged signal's (before companding)."""
        return self.merge.black_level_dn if self.merge else self.readouts[0].black_level_dn

    @property
    def saturation_dn(self) -> float:
        """The linear signal above black (DN of the first readout) at saturation."""
        return self.merge.saturation_dn(self.readouts) if self.merge else self.readouts[0].saturation_dn

    @property
    def saturation_e(self) -> float:
        """The reference photodiode's photo-electrons at saturation (`auto_exposure`)."""
        first = self.readouts[0]
        return self.saturation_dn / (first.gain_dn_per_e * first.response)

    @property
    def dark_current_e_s(self) -> float:
        """The first readout's dark current (e⁻/s)."""
        return self.readouts[0].dark_current_e_s

    def linear_dn(self, raw: np.ndarray) -> np.ndarray:
        """The linear signal above black of a RAW: decompanded (the image processor's inverse).

        Parameters
        ----------
        raw : numpy.ndarray
            A RAW frame of this sensor (DN).

        Returns
        -------
        numpy.ndarray
            float64, DN of the first readout above black.
        """
        linear = self.compander.decompand(raw) if self.compander is not None else np.asarray(raw, dtype=np.float64)
        return linear - self.black_level_dn

    def saturated(self, raw: np.ndarray) -> np.ndarray:
        """Where a RAW is saturated: the last readout within 3 σ of its readout noise of its saturation.

        Parameters
        ----------
        raw : numpy.ndarray
            A RAW frame of this sensor (DN).

        Returns
        -------
        numpy.ndarray
            bool, True where saturated.
        """
        last = self.readouts[-1]
        spread = emva.saturation_spread_dn(last.gain_dn_per_e, last.read_noise_e, last.dsnu_e)
        scale = self.saturation_dn / last.saturation_dn
        return self.linear_dn(raw) >= self.saturation_dn - spread * scale


def _photons(values: dict) -> PhotonConversion:
    """The photon conversion of a `[sensor]` table whose readouts are tables of their own."""
    head = set(PhotonConversion.field_names())
    unknown = sorted(set(values) - head)
    if unknown:
        raise SolasError(f"unknown sensor parameter(s) {', '.join(unknown)}; allowed: "
                         f"{', '.join(sorted(head | set(STAGES.names()) - {HEAD}))}")
    values = {k: tuple(v) if isinstance(v, list) else v for k, v in values.items()}
    if "qe_curve" in values:
        values["qe_curve"] = QECurve.from_table(values["qe_curve"], "sensor qe_curve")
    return _made(HEAD, values)


def _made(kind: str, table):
    """A stage of kind `kind` from its TOML table; an unknown name is an error naming the stage's fields."""
    cls: Any = STAGES[kind].function  # a stage's dataclass
    if not isinstance(table, dict):
        raise SolasError(f"sensor {kind} must be a table of {cls.__name__}'s fields")
    known = list(cls.__dataclass_fields__)
    unknown = sorted(set(table) - set(known))
    if unknown:
        raise SolasError(f"unknown sensor {kind} parameter(s) {', '.join(unknown)}; allowed: {', '.join(known)}")
    return cls(**table)


def chain_of(model) -> SensorChain:
    """The chain of a flat sensor (`model.SensorModel`): its photon conversion and its one readout."""
    own = set(Readout.field_names()) & {f.name for f in fields(model)}  # noise, well, gain, ADC
    return SensorChain(model.photons, (Readout(**{name: getattr(model, name) for name in own}),))
