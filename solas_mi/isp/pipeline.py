"""`ISP`: the image processor's description, and `develop`, a RAW frame → an 8-bit sRGB frame.

The stages, in order, each optional and named in the metadata:

1. black level (`black`): the signal above black as a fraction of saturation (an HDR sensor's RAW
   decompanded first), its defect pixels replaced by their neighbours' mean (`defects`);
2. white balance (`white.METHODS`): one gain per filter on the mosaic;
3. demosaicing (`demosaic.METHODS`): three channels per pixel (``none``: the mosaic as a grey frame);
4. colour correction (`ccm`): the sensor's matrix, a given one, or none;
5. tone curve (`tone.CURVES`), then 8 bits.

An `ISP` is written ``default`` (every field's default) or as a small TOML file with an ``[isp]``
table of its fields, e.g.

    [isp]
    white_balance = "grey-card"   # a name of white.METHODS, or gains {R = 1.9, G = 1, B = 1.5}
    grey_card = [100, 80, 140, 120]  # x0, y0, x1, y1 (pixels) with grey-card
    demosaic = "Menon2007"        # a name of demosaic.METHODS, or none
    demosaic_options = {refining_step = false}  # the method's own options
    ccm = "sensor"                # sensor, none, or [[...], [...], [...]]
    tone = "gamma"                # a name of tone.CURVES
    gamma = 2.2                   # the gamma curve's option
"""
from __future__ import annotations

import os
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SolasError
from ..options import toml_table
from ..sensor.chain import SensorChain
from ..sensor.model import SensorModel
from . import black, ccm, defects, demosaic, tone, white
from .tone import CURVES, DEFAULT_CURVE, GAMMA

DEFAULT = "default"


@dataclass(frozen=True)
class ISP:
    """The image processor: each stage's choice, checked when built ([the image processor](../details/isp.md)).

    Parameters
    ----------
    black_level : bool, default True
        Subtract the black level (the signal becomes a fraction of saturation).
    defect_correction : bool, default True
        Replace a sensor's defect pixels by their same-filter neighbours' mean (with a defect map).
    white_balance : str or dict, default: `white.METHODS`'s default
        A name of `white.METHODS`, or gains per filter ({"R": 1.9, "G": 1.0, "B": 1.5}).
    grey_card : (int, int, int, int), optional
        The grey card's box x0, y0, x1, y1 (pixels), with white_balance "grey-card" only.
    demosaic : str, default: `demosaic.METHODS`'s default
        A name of `demosaic.METHODS`, or "none" (the mosaic as a grey frame).
    demosaic_options : dict, optional
        The demosaicing method's own options.
    ccm : str or tuple, default "sensor"
        The colour correction: "sensor" (from the sensor's channel responses), "none", or a 3 × 3 matrix.
    tone : str, default: `tone.CURVES`'s default
        A name of `tone.CURVES`.
    gamma : float, default: the gamma curve's
        The "gamma" curve's exponent.

    Raises
    ------
    SolasError
        For a name not in its registry, an option the method does not take, or options that do not go
        together (a grey card without "grey-card", a CCM with demosaic "none").

    Examples
    --------
    >>> from solas_mi.isp import ISP
    >>> ISP(demosaic="bilinear", tone="gamma", gamma=2.4).describe()["gamma"]
    2.4
    """

    black_level: bool = True
    defect_correction: bool = True
    white_balance: str | dict = white.DEFAULT_METHOD
    grey_card: tuple[int, int, int, int] | None = None
    demosaic: str = demosaic.DEFAULT_METHOD
    demosaic_options: dict = field(default_factory=dict)
    ccm: str | tuple = "sensor"
    tone: str = DEFAULT_CURVE
    gamma: float = GAMMA.default

    def __post_init__(self):
        for name in ("black_level", "defect_correction"):
            if not isinstance(getattr(self, name), bool):
                raise SolasError(f"isp {name} {getattr(self, name)!r} must be true or false")
        self._check_white_balance()
        if not isinstance(self.demosaic, str) or self.demosaic != "none":
            demosaic.check_method(self.demosaic, self.demosaic_options)
        elif self.ccm != "none" or self.demosaic_options != {}:
            raise SolasError("isp demosaic = \"none\" gives a grey frame: it takes ccm = \"none\" and no demosaic_options")
        if not isinstance(self.ccm, str):
            object.__setattr__(self, "ccm", tuple(map(tuple, ccm.check_matrix(self.ccm))))
        elif self.ccm not in ("sensor", "none"):
            raise SolasError(f"isp ccm {self.ccm!r} must be sensor, none, or a 3 × 3 matrix")
        tone.check_curve(self.tone, self.gamma)

    def _check_white_balance(self) -> None:
        """A method's name or a table of gains; a grey card's box with grey-card, and only with it."""
        named = white.named()
        if isinstance(self.white_balance, dict):
            white.check_gains(self.white_balance)
        elif not isinstance(self.white_balance, str) or self.white_balance not in named:
            raise SolasError(f"isp white_balance {self.white_balance!r} must be one of {', '.join(named)}, "
                             "or a table of gains per filter")
        if (self.white_balance == "grey-card") != (self.grey_card is not None):
            raise SolasError("isp grey_card (x0, y0, x1, y1) goes with white_balance = \"grey-card\", and only with it")
        if self.grey_card is not None:
            object.__setattr__(self, "grey_card", white.check_box(self.grey_card))

    @classmethod
    def from_dict(cls, values: dict) -> ISP:
        """An image processor from a mapping of field names (an ``[isp]`` table).

        Parameters
        ----------
        values : dict
            Field name → value.

        Returns
        -------
        ISP
            The processor, checked.

        Raises
        ------
        SolasError
            For an unknown name or a bad value.
        """
        known = [f.name for f in fields(cls)]
        unknown = sorted(set(values) - set(known))
        if unknown:
            raise SolasError(f"unknown isp option(s) {', '.join(unknown)}; allowed: {', '.join(known)}")
        return cls(**values)

    def describe(self) -> dict:
        """Every field as JSON values, for metadata.

        Returns
        -------
        dict
            Field name → value (tuples as lists).
        """
        return {k: list(map(list, v)) if k == "ccm" and isinstance(v, tuple) else list(v) if isinstance(v, tuple) else v
                for k, v in asdict(self).items()}


def load_isp(text: str | Path) -> ISP:
    """An image processor: ``default``, or one from a TOML file.

    Parameters
    ----------
    text : str or Path
        "default" (every field's default), or a TOML file of one ``[isp]`` table of `ISP`'s fields.

    Returns
    -------
    ISP
        The processor, checked.

    Raises
    ------
    SolasError
        For a file that does not exist or cannot be read, or a bad value (naming the file).

    Examples
    --------
    >>> from solas_mi.isp import ISP, load_isp
    >>> load_isp("default") == ISP()
    True
    """
    if str(text) == DEFAULT:
        return ISP()
    if not os.path.lexists(text):
        raise SolasError(f"isp {str(text)!r} must be 'default' or a TOML file with an [isp] table (no such file)")
    values = toml_table(text, "isp", "isp file")
    try:
        if "gamma" in values and values.get("tone") != "gamma":
            raise SolasError(f"isp gamma = {values['gamma']!r} goes with tone = \"gamma\" (tone here: "
                             f"{values.get('tone', ISP.tone)!r}); give both, or neither")
        return ISP.from_dict(values)
    except SolasError as exc:
        raise SolasError(f"isp file {str(text)!r}: {exc}") from None


def _white_balance(isp: ISP) -> str:
    """The name of the ISP's white-balance method (`white.METHODS`)."""
    return white.GIVEN if isinstance(isp.white_balance, dict) else isp.white_balance


def check_sensor(isp: ISP, model: SensorModel) -> None:
    """SolasError before any frame is taken where `isp` cannot develop the frames of sensor `model`: white
    balance gains given for other filters than its colour filter array's (develop would refuse every
    frame, after its work)."""
    if isinstance(isp.white_balance, dict):
        white.check_given(isp.white_balance, model.cfa)


def develop(raw: np.ndarray, model: SensorModel | SensorChain, isp: ISP = ISP(),
            defective: np.ndarray | None = None) -> tuple[np.ndarray, dict]:
    """Develop a RAW frame into an 8-bit sRGB frame: black level, white balance, demosaic, CCM, tone.

    Parameters
    ----------
    raw : numpy.ndarray
        (H, W) DN, the sensor's mosaic (`sensor.capture.capture`).
    model : SensorModel or SensorChain
        The sensor that took it (an HDR sensor's RAW is decompanded first).
    isp : ISP, default ISP()
        The image processor.
    defective : numpy.ndarray, optional
        The sensor's defect map (`SensorChain.defective_pixels`): those pixels take their same-filter
        neighbours' mean (`defects`); None: no defects.

    Returns
    -------
    frame : numpy.ndarray
        (H, W, 3) uint8.
    meta : dict
        The processor and every stage with the values it used.

    Examples
    --------
    >>> import numpy as np
    >>> from solas_mi.isp import develop
    >>> from solas_mi.sensor import load_sensor
    >>> sensor = load_sensor("ar0132at")
    >>> frame, meta = develop(np.full((8, 12), 2000, np.uint16), sensor)
    >>> frame.shape, frame.dtype.name, sorted(meta["stages"])
    ((8, 12, 3), 'uint8', ['black_level', 'ccm', 'demosaic', 'tone', 'white_balance'])
    """
    stages: dict[str, dict[str, Any]] = {"black_level": {"subtracted": isp.black_level, "black_dn": model.black_level_dn,
                              "saturation_dn": black.saturation_dn(model),
                              "decompanded_through": black.decompanded_through(model)}}
    signal = black.subtract_black(raw, model, enabled=isp.black_level)
    signal, stages["black_level"]["defect_pixels_corrected"] = defects.correct(
        signal, defective if isp.defect_correction else None)
    gains = white.METHODS[_white_balance(isp)].function(signal, model, isp)
    stages["white_balance"] = {"method": _white_balance(isp), "gains": gains,
                               **({"grey_card": list(isp.grey_card)} if isp.grey_card else {})}
    signal = white.apply_gains(signal, model.cfa, gains)
    if isp.demosaic == "none":
        image = np.repeat(signal[..., None], 3, axis=-1)
    else:
        image = demosaic.demosaic(signal, model.cfa, isp.demosaic, **isp.demosaic_options)
    stages["demosaic"] = {"method": isp.demosaic, "options": dict(isp.demosaic_options),
                          "cfa": model.cfa, "channels": list(demosaic.slots(model.cfa)[1])}
    matrix = _matrix(isp, model)
    if matrix is not None:
        image = ccm.correct(image, matrix)
    stages["ccm"] = {"method": isp.ccm if isinstance(isp.ccm, str) else "given",
                     "matrix": None if matrix is None else matrix.tolist()}
    clipped = int(np.count_nonzero((image < 0.0) | (image > 1.0)))
    frame = tone.to_8bit(tone.encode(image, isp.tone, isp.gamma))
    own = {o.name: getattr(isp, o.name) for o in CURVES[isp.tone].options}  # an ISP field per curve option
    stages["tone"] = {"curve": isp.tone, **own,
                      "values_clipped": clipped, "bits": 8}
    return frame, {"isp": isp.describe(), "stages": stages}


def _matrix(isp: ISP, model: SensorModel | SensorChain) -> np.ndarray | None:
    if isp.ccm == "none":
        return None
    if isp.ccm == "sensor":
        return ccm.sensor_matrix(model, white.channel_gains(model.cfa, white.daylight_gains(model)))
    return np.array(isp.ccm)
