"""A sensor described in a small TOML file: a `[sensor]` table of `SensorModel`'s field names, e.g.

    [sensor]
    pixel_pitch_um = 3.0
    qe_r = 0.55
    cfa = "RCCB"

Fields left out take `SensorModel`'s values; `describe` lists every value used (the RAW's metadata)."""
from dataclasses import asdict
from pathlib import Path

from ..errors import SolasError
from ..options import toml_table
from .model import SensorModel


def load_sensor(path: str | Path) -> SensorModel:
    """The `SensorModel` of the `[sensor]` table of TOML file `path`."""
    values = toml_table(path, "sensor", "sensor model")
    try:
        return SensorModel.from_dict(values)
    except SolasError as exc:
        raise SolasError(f"sensor model {str(path)!r}: {exc}") from None


def describe(model: SensorModel) -> dict:
    """Every parameter of `model` (JSON-ready), for metadata."""
    return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(model).items()}
