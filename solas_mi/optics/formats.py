"""The lens file formats: which reader turns a file's text into the lens-file dictionary
(`Lens.from_dict`), which writer turns a `Lens` into text, by extension, and how other programs' files
are decoded; which file a lens name or path means (`lens_path`). Our TOML is read by `Lens.load` itself.
"""
from __future__ import annotations

import math
import os
import re
from pathlib import Path

from ..errors import SolasError
from ..resources import resource_dir
from . import lens_toml, pbrt_dat

LENS_DIR = "lenses"
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f\u2028\u2029]")

# Lens file formats, in the order messages list them
FORMATS = (".toml", ".zmx", ".seq", ".dat")
# Formats besides our TOML: text → lens-file dictionary, and Lens → text. The readers of other
# programs' files (`zemax`: .zmx, `codev`: .seq), which solve apertures and fields with the tracer,
# add themselves when `solas_mi.optics` is imported (the tracer imports this module).
READERS = {".dat": pbrt_dat.read_spec}
# What a lens read from a format must hold beyond any lens's checks: a .dat table, what pbrt can trace
READ_CHECKS = {".dat": pbrt_dat.check_read}
WRITERS = {".toml": lens_toml.dumps, ".dat": pbrt_dat.dumps}


def decode_text(data: bytes) -> str:
    """The text of another program's lens file: UTF-16 by its byte-order mark, or without one when
    NULs fill every other byte of the start (OpticStudio's Unicode files), UTF-8 (with or without a
    BOM), else Latin-1 (OpticStudio's ANSI files, older tables)."""
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return data.decode("utf-16", errors="replace")
    head = data[:200]
    for start, codec in ((1, "utf-16-le"), (0, "utf-16-be")):
        if len(head) >= 4 and head[start::2].count(0) >= 0.9 * (len(head) // 2):
            return data.decode(codec, errors="replace")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def one_line(text: str) -> str:
    """`text` with every line break and control character made a space: what a line of another program's
    lens file may hold."""
    return _CONTROL.sub(" ", text)


def floats(tokens: list[str], where: str) -> list[float]:
    """The numbers of a line's tokens (other programs' lens files), finite; else SolasError naming `where`."""
    try:
        values = [float(t) for t in tokens]
    except ValueError:
        raise SolasError(f"{where}: expected numbers, got {' '.join(tokens)!r}") from None
    if not all(math.isfinite(v) for v in values):
        raise SolasError(f"{where}: {' '.join(tokens)!r} must be finite numbers")
    return values


def listed(formats) -> str:
    """The extensions of `formats` that FORMATS lists, in its order, comma-separated."""
    return ", ".join(e for e in FORMATS if e in formats)


def _shipped_dir() -> Path:
    return resource_dir("scenes") / LENS_DIR


def shipped_lenses() -> list[str]:
    """Names of the lenses that ship with solas-mi (`Lens.load` takes them)."""
    return sorted(p.stem.replace("_", "-") for p in _shipped_dir().glob("*.toml"))


def lens_path(name_or_path) -> Path:
    """The lens file a shipped name (e.g. "solas-doublet") or a path means, checked to exist and to have a
    lens extension: a name holding a path separator or an extension is a path."""
    if not isinstance(name_or_path, (str, os.PathLike)):
        raise SolasError(f"lens {name_or_path!r} must be a shipped lens name ({', '.join(shipped_lenses())}) "
                         f"or a path to a lens file ({listed(READERS.keys() | {'.toml'})})")
    given = os.fspath(name_or_path)
    path = Path(given)
    if not path.suffix and not any(sep and sep in given for sep in (os.sep, os.altsep, "/")):
        path = _shipped_dir() / (given.replace("-", "_") + ".toml")
        if not path.is_file():
            raise SolasError(f"unknown lens {given!r}; shipped lenses: {', '.join(shipped_lenses())}, or a path "
                             f"to a lens file ({listed(READERS.keys() | {'.toml'})})")
    if path.suffix.lower() not in READERS.keys() | {".toml"}:
        what = f"unknown extension {path.suffix!r}" if path.suffix else "no lens extension"
        raise SolasError(f"lens file {given!r} has {what}; allowed: {listed(READERS.keys() | {'.toml'})}")
    if path.is_dir():
        raise SolasError(f"lens file {given!r} is a folder, not a lens file")
    if not path.is_file():
        raise SolasError(f"lens file {str(path)!r} does not exist")
    return path
