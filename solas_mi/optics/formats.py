"""The lens file formats: `READERS`, extension → the reader that turns a file into the lens-file
dictionary (`Lens.from_dict`), and `WRITERS`, extension → the writer that turns a `Lens` into text (each a
`solas_mi.registry.Registry`, filled in one place: the package's `__init__`, before any module of it is
used); how other programs' files are decoded; which file a lens name or path means (`lens_path`).
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path

from ..errors import SolasError
from ..registry import Registry
from ..resources import resource_dir
from ..userfiles import check, read_bytes, read_toml

LENS_DIR = "lenses"
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f\u2028\u2029]")

# by extension, in the order messages list them: path → lens-file dictionary (a reader's `check`: what a
# lens read from that format must hold beyond any lens's checks), and Lens → text. The readers of other
# programs' files solve apertures and fields with the tracer, which imports this module: they are
# registered by `solas_mi.optics` itself (`__init__`), which Python runs before any of its modules is used.
READERS = Registry("lens reader")
WRITERS = Registry("lens writer")


def read_toml_lens(path: Path) -> dict:
    """Our TOML lens file's dictionary."""
    return read_toml(path, "lens file")


def text_reader(read_spec):
    """The reader of another program's lens file whose text `read_spec(text, where)` parses: the file
    decoded as `decode_text` says."""

    def read(path: Path) -> dict:
        return read_spec(decode_text(read_bytes(path, "lens file")), str(path))

    return read


# The most a lens may hold, in every reader and in `Lens` itself. A trace is one Dr.Jit kernel through
# every surface, whose compile time grows faster than the surfaces (`lens info`: 100 surfaces ~30 s on 2
# cores, 300 ~4 min) and whose assembly recurses once per variable of a ray's chain of operations
# (`jitc_var_traverse`, ~50 variables and ~5 KiB of stack a surface): ~1 600 surfaces overflow an 8 MiB
# stack, a segmentation fault. The wavelengths and a file's fields each multiply the traces of `lens info`
# and of the readers' solves (64 wavelengths and 200 fields of a .zmx with automatic apertures: ~10 s).
# Real lenses: up to ~60 surfaces (lithography objectives ~80), 3 to 25 fields; the visible at 10 nm
# steps is 41 wavelengths.
MAX_SURFACES = 128
MAX_WAVELENGTHS = 64
MAX_FIELDS = 200


def check_count(count: int, what: str, most: int, where: str) -> None:
    """SolasError naming `where` unless `count` (of surfaces, wavelengths, fields: `what`) is at most `most`."""
    if count > most:
        raise SolasError(f"{where}: {count} {what}; a lens may have at most {most}")


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


def check_printable(text: str, what: str, where: str) -> None:
    """SolasError unless `text` (a lens's name, description or a surface's label: printed by `lens info` and in
    metadata) holds no line break nor control character: an escape sequence would drive the terminal."""
    if _CONTROL.search(text):
        raise SolasError(
            f"{where}: the {what} {text!r} holds control characters; it must be printable text on one line"
        )


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


def readable() -> str:
    """The lens file extensions `Lens.load` reads (`READERS`), comma-separated: what every message and help
    text that lists lens files says."""
    return ", ".join(READERS)


def writable() -> str:
    """The lens file extensions `Lens.save` writes (`WRITERS`), comma-separated."""
    return ", ".join(WRITERS)


def lens_help() -> str:
    """What a lens argument or option takes, for help texts."""
    return f"a shipped lens name (e.g. solas-doublet; `solas-mi lens list`) or a lens file ({readable()})"


def _shipped_dir() -> Path:
    return resource_dir("scenes") / LENS_DIR


def shipped_lenses() -> list[str]:
    """Names of the lenses that ship with solas-mi (`Lens.load` takes them)."""
    return sorted(p.stem.replace("_", "-") for p in _shipped_dir().glob("*.toml"))


def lens_path(name_or_path) -> Path:
    """The lens file a shipped name (e.g. "solas-doublet") or a path means, checked to exist and to have a
    lens extension: a name holding a path separator or an extension is a path."""
    if not isinstance(name_or_path, (str, os.PathLike)):
        raise SolasError(
            f"lens {name_or_path!r} must be a shipped lens name ({', '.join(shipped_lenses())}) "
            f"or a path to a lens file ({readable()})"
        )
    given = os.fspath(name_or_path)
    path = Path(given)
    if not path.suffix and not any(sep and sep in given for sep in (os.sep, os.altsep, "/")):
        path = _shipped_dir() / (given.replace("-", "_") + ".toml")
        if not path.is_file():
            raise SolasError(
                f"unknown lens {given!r}; shipped lenses: {', '.join(shipped_lenses())}, or a path "
                f"to a lens file ({readable()})"
            )
    if path.suffix.lower() not in READERS:
        what = f"unknown extension {path.suffix!r}" if path.suffix else "no lens extension"
        raise SolasError(f"lens file {given!r} has {what}; allowed: {readable()}")
    return check(path, "lens file")
