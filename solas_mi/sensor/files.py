"""A sensor described in a small TOML file, or one of the presets shipped with the package: a
`[sensor]` table of `SensorModel`'s field names, e.g.

    [sensor]
    pixel_pitch_um = 3.0
    qe_r = 0.55
    cfa = "RCCB"

Fields left out take `SensorModel`'s values; `describe` lists every value used (the RAW's metadata). A
sensor of several readouts (HDR) names its stages after the photon conversion's fields: `[[sensor.readout]]`
tables, a `[sensor.merge]` and a `[sensor.compander]` (`chain`); it loads as a `chain.SensorChain`.
Instead of `qe_r`, `qe_g`, `qe_b`, `qe_c` and `wavelengths_nm`, a sensor may give its filters' quantum
efficiency against wavelength (`qe.QECurve`): `qe_curve = "curve.csv"` (a CSV file beside the TOML
file, `qe.read_csv`) or a `[sensor.qe_curve]` table of columns `wavelength_nm`, `R`, `G`, `B`, `C`.

`load_sensor(name_or_path)` takes a preset's name (`preset_names`: the TOML files of
`solas_mi/sensor/presets/`, each citing its sources) or the path of a TOML file (a name ending in
".toml" or holding a path separator)."""

import os
from dataclasses import asdict
from pathlib import Path

from ..errors import SolasError
from ..options import toml_table
from .chain import HEAD, STAGES, SensorChain
from .model import SensorModel
from .qe import read_csv

PRESETS = Path(__file__).resolve().parent / "presets"


def preset_names() -> list[str]:
    """The names of the shipped sensor presets, sorted."""
    return sorted(p.stem for p in PRESETS.glob("*.toml"))


def preset_title(name: str) -> str:
    """The first line of preset `name`'s file, a comment naming the sensor (without the "# ")."""
    first = (PRESETS / f"{name}.toml").read_text(encoding="utf-8").splitlines()[0]
    return first.lstrip("# ").strip()


def _path(name_or_path: str | Path) -> Path:
    """The TOML file of a preset name or a path (module docstring)."""
    text = str(name_or_path)
    if isinstance(name_or_path, Path) or text.endswith(".toml") or os.sep in text or "/" in text:
        return Path(name_or_path)
    if text not in preset_names():
        raise SolasError(f"sensor model {text!r} is neither a preset ({', '.join(preset_names())}) nor a .toml file")
    return PRESETS / f"{text}.toml"


def load_sensor(name_or_path: str | Path) -> SensorModel | SensorChain:
    """A sensor from a shipped preset or a TOML file.

    Parameters
    ----------
    name_or_path : str or Path
        A preset's name (`preset_names`: ``solas-mi sensors``), or the path of a TOML file of one
        ``[sensor]`` table of `SensorModel`'s field names, or naming its stages (`chain`) (a name ending in
        ".toml" or holding a path separator).

    Returns
    -------
    SensorModel or SensorChain
        The sensor, checked: a `SensorChain` where the table names stages (an HDR sensor).

    Raises
    ------
    SolasError
        For an unknown preset, a file that cannot be read, or a bad value (naming the file).

    Examples
    --------
    >>> from solas_mi.sensor import load_sensor
    >>> sensor = load_sensor("ar0132at")
    >>> sensor.pixel_pitch_um, sensor.cfa
    (3.75, 'RGGB')
    """
    path = _path(name_or_path)
    values = dict(toml_table(path, "sensor", "sensor model"))
    try:
        if isinstance(values.get("qe_curve"), str):  # a CSV file, relative to the TOML file
            if not values["qe_curve"].strip():  # else the sensor file's folder, refused as "a folder"
                raise SolasError(
                    "sensor qe_curve = '' must name a CSV file (beside the sensor file) or be a "
                    "[sensor.qe_curve] table of columns"
                )
            values["qe_curve"] = read_csv(path.parent / values["qe_curve"]).table()
        if set(values) & (set(STAGES) - {HEAD}):  # the table names stages
            return SensorChain.from_dict(values)
        return SensorModel.from_dict(values)
    except SolasError as exc:
        raise SolasError(f"sensor model {str(path)!r}: {exc}") from None


def describe(model: SensorModel | SensorChain) -> dict:
    """Every parameter of `model` (JSON-ready; a QE curve as its table of columns), for metadata: a chain's
    stages in order."""
    if isinstance(model, SensorChain):
        return model.describe()
    values = {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(model).items() if k != "qe_curve"}
    values["qe_curve"] = None if model.qe_curve is None else model.qe_curve.table()
    return values
