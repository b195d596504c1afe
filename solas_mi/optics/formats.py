"""The lens file formats: which reader turns a file's text into the lens-file dictionary
(`Lens.from_dict`), which writer turns a `Lens` into text, by extension, and how other programs' files
are decoded. Our TOML is read by `Lens.load` itself.
"""
from __future__ import annotations

import math

from ..errors import SolasError
from . import lens_toml, pbrt_dat

# Lens file formats, in the order messages list them
FORMATS = (".toml", ".zmx", ".seq", ".dat")
# Formats besides our TOML: text → lens-file dictionary, and Lens → text. The readers of other
# programs' files (`zemax`: .zmx, `codev`: .seq), which solve apertures and fields with the tracer,
# add themselves when `solas_mi.optics` is imported (the tracer imports this module).
READERS = {".dat": pbrt_dat.read_spec}
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
