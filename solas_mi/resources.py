"""Where the shipped scenes/ and plugins/ folders are, in a source checkout or an installed wheel."""
from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent


def resource_dir(name: str) -> Path:
    """Path of the top-level folder `name` ("scenes" or "plugins"): beside the package in a source
    checkout, inside it (as solas_mi/<name>) once installed from a wheel."""
    local = _PACKAGE.parent / name
    return local if local.is_dir() else _PACKAGE / name
