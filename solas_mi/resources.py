"""Where the shipped scenes/ and plugins/ folders are, in a source checkout or an installed wheel."""
from __future__ import annotations

from importlib.resources import files
from pathlib import Path


def resource_dir(name: str) -> Path:
    """Path of the top-level folder `name` ("scenes" or "plugins")."""
    local = Path(__file__).resolve().parent.parent / name
    if local.is_dir():
        return local
    return Path(str(files(f"solas_mi.{name}")))
