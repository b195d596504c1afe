"""Every file that a user or another file names is checked, and read, here: lens files, sensor models,
ISP files, QE curves, camera response tables, images, scenes and the files they name, a batch's
manifest and the cache's records.

The guarantees, the same for each: only a regular file is read — a folder, a device (/dev/zero), a FIFO
or a socket is refused before anything is read, and a FIFO is opened without waiting for a writer; at
most its kind's bound (`LIMITS`, stated in the refusal) is read, even from a file whose size the system
does not know (/proc); text is UTF-8 without NUL bytes; a TOML file nests at most `MAX_NESTING` levels;
and no refusal quotes what the file holds (a file another file names may be anything the user can read,
/proc/self/environ included). Files that a library reads by path (images, Mitsuba's meshes) are
`check`ed the same way first.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import Any

from .errors import SolasError

MIB = 1 << 20
# The most bytes a file of each kind may hold (the name is how messages call the file). Lens files and
# tables are small text (a Zemax file of 128 surfaces, UTF-16, is ~120 KiB; a file at the bound is refused
# by its count of surfaces in ~1 s); images and a scene's meshes and textures are bounded by memory,
# which the commands estimate from their headers (`budget`).
LIMITS = {
    "lens file": 1 * MIB,
    "tolerance file": 1 * MIB,  # a lens's tolerances (`optics.tolerance`)
    "calibration file": 1 * MIB,  # a camera calibration (OpenCV, OCamCalib, WoodScape, Kalibr)
    "sensor model": 1 * MIB,
    "isp file": 1 * MIB,
    "QE curve": 4 * MIB,
    "camera response table": 4 * MIB,
    "record": 64 * MIB,  # JSON a run wrote and a later one reads (a batch's manifest, a cache entry's record)
    "annotations file": 256 * MIB,  # a frame's boxes and keypoints (COCO's JSON layout), `labelkinds`
    "scene file": 64 * MIB,  # a Mitsuba scene's XML
    "scene data file": 16384 * MIB,  # a mesh, texture or spectrum a scene names (Mitsuba reads it)
    "image file": 16384 * MIB,
    "batch input": 16384 * MIB,  # an image or scene file given to a batch by name (then read as its kind)
}
MAX_NESTING = 16  # levels of tables and arrays in a TOML file (ours need 4)


def _size(n: int) -> str:
    return f"{n // (1 << 30)} GiB" if n >= 1 << 30 else f"{n // MIB} MiB" if n >= MIB else f"{n} bytes"


def _a(kind: str) -> str:
    return ("an " if kind[0].lower() in "aeio" else "a ") + kind


def _too_big(path: Path, kind: str) -> SolasError:
    return SolasError(f"{kind} {str(path)!r} is larger than {_size(LIMITS[kind])}, the most {_a(kind)} may hold")


def _check_stat(info: os.stat_result, path: Path, kind: str) -> None:
    if stat.S_ISDIR(info.st_mode):
        raise SolasError(f"{kind} {str(path)!r} is a folder, not {_a(kind)}")
    if not stat.S_ISREG(info.st_mode):
        raise SolasError(
            f"{kind} {str(path)!r} is not a regular file (a device, FIFO or socket); "
            f"{_a(kind)} must be a regular file of at most {_size(LIMITS[kind])}"
        )
    if info.st_size > LIMITS[kind]:
        raise _too_big(path, kind)


def _unreadable(path: Path, kind: str, exc: OSError) -> SolasError:
    if isinstance(exc, FileNotFoundError):
        return SolasError(f"{kind} {str(path)!r} does not exist")
    return SolasError(f"{kind} {str(path)!r} cannot be read: {exc.strerror or type(exc).__name__}")


def check(path: str | os.PathLike, kind: str) -> Path:
    """`path` as a Path once it names a regular file of at most `LIMITS[kind]` bytes (symbolic links
    followed); SolasError naming the path and what is allowed otherwise. For files a library opens."""
    p = Path(path)
    try:
        info = os.stat(p)
    except OSError as exc:
        raise _unreadable(p, kind, exc) from None
    except ValueError:  # a NUL in the name
        raise SolasError(f"{kind} {str(p)!r} is not a file name (it holds a NUL character)") from None
    _check_stat(info, p, kind)
    return p


def read_bytes(path: str | os.PathLike, kind: str) -> bytes:
    """The bytes of the regular file `path`, at most `LIMITS[kind]` of them (`check`'s refusals; the
    bound also holds for a file that grows or reports no size)."""
    p = check(path, kind)  # nothing opened that is not a regular file: a device's open can act
    try:
        fd = os.open(p, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise _unreadable(p, kind, exc) from None
    try:
        _check_stat(os.fstat(fd), p, kind)  # the file opened is the one checked
        with os.fdopen(fd, "rb", closefd=False) as f:
            data = f.read(LIMITS[kind] + 1)
    except OSError as exc:
        raise _unreadable(p, kind, exc) from None
    finally:
        os.close(fd)
    if len(data) > LIMITS[kind]:
        raise _too_big(p, kind)
    return data


def read_text(path: str | os.PathLike, kind: str) -> str:
    """The UTF-8 text (a byte-order mark allowed) of the file `path` (`read_bytes`); SolasError, quoting
    nothing of it, when it holds NUL bytes (UTF-16, binary) or is not UTF-8."""
    data = read_bytes(path, kind)
    why = "it holds NUL bytes: UTF-16 or binary" if b"\0" in data else None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        why = why or f"byte {exc.start + 1} is not UTF-8: Latin-1 or binary"
    if why:
        raise SolasError(f"{kind} {str(path)!r} is not UTF-8 text ({why}); {_a(kind)} is UTF-8 text")
    return text


def _nested(value: Any, levels: int) -> bool:
    """Whether `value` nests tables and arrays deeper than `levels`."""
    if not isinstance(value, (dict, list)):
        return False
    if levels == 0:
        return True
    return any(_nested(v, levels - 1) for v in (value.values() if isinstance(value, dict) else value))


def read_toml(path: str | os.PathLike, kind: str) -> dict:
    """The TOML file `path` (`read_text`) parsed; SolasError for invalid TOML (the parser's message: what
    it expected, and where) and for tables and arrays nested deeper than `MAX_NESTING`."""
    import tomllib

    text = read_text(path, kind)
    deep = SolasError(f"{kind} {str(path)!r} nests tables and arrays more than {MAX_NESTING} levels deep")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SolasError(f"{kind} {str(path)!r} is not valid TOML: {exc}") from None
    except RecursionError:  # thousands of levels: deeper than the parser goes
        raise deep from None
    if _nested(data, MAX_NESTING):
        raise deep
    return data
