"""Where the commands write, checked before any work is done, and how: a data file (OpenEXR) and its
preview (PNG) replaced together or not at all.

The guarantees: no output replaces an input of the same command; an output is a new name or an
existing regular file (never a folder, a device or a symbolic link, which would be replaced by a
plain file); the data file is always OpenEXR and its preview never collides with it or with an
input; the output's folder is writable before the computation starts. Writes go to temporary files
beside the targets, renamed into place at the end (`imageio.atomic_path`), and removed on any error
or interruption.
"""

from __future__ import annotations

import os
import re
import unicodedata
from collections.abc import Iterable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

from .errors import SolasError

_UNSAFE = re.compile(r"[^\w.+=-]+")  # \w: the letters and digits of every script, and _
NAME_MAX = 120  # UTF-8 bytes of a name component (file systems allow 255; room for suffixes)


def safe_name(text: object, fallback: str = "item") -> str:
    """`text` (a lens name, an item name, a sweep value: user data) as one safe file-name component:
    every run of characters other than letters, digits (of any script: "café", "東京") and . _ + = -
    becomes "_" (so no separator, NUL, newline, space or control character; accents composed first, NFC),
    no leading dot (no hidden file, no "." or ".."), at most NAME_MAX bytes in UTF-8 (cut between characters); `fallback` when
    nothing is left."""
    name = _UNSAFE.sub("_", unicodedata.normalize("NFC", str(text))).lstrip("._") if text is not None else ""
    name = name.encode("utf-8")[:NAME_MAX].decode("utf-8", errors="ignore").rstrip("_")
    return name or fallback


def inside(folder: str | os.PathLike, name: str) -> Path:
    """`folder`/`name`, SolasError unless it lies directly inside `folder` after resolution (symbolic
    links and ".." followed): where an output named from user data may be written."""
    base = Path(folder).resolve()
    path = base / name
    if path.resolve().parent != base:
        raise SolasError(
            f"output name {name!r} leads outside the folder {base}; names derived from "
            "user data must be plain file names"
        )
    return path


def _same(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve() or (a.exists() and b.exists() and os.path.samefile(a, b))
    except OSError:
        return False


def _writable_folder(path: Path) -> None:
    folder = path.parent if str(path.parent) else Path(".")
    existing = next(p for p in (folder, *folder.parents) if p.exists())
    if not existing.is_dir():
        raise SolasError(f"cannot write {path}: {existing} is not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise SolasError(f"cannot write {path}: folder {existing} is not writable")


def check_target(path: str | os.PathLike, inputs: Iterable[str | os.PathLike] = (), what: str = "output") -> Path:
    """`path` as a Path after checking it may be written: not an input, a new name or a regular file,
    in a writable folder."""
    p = Path(path)
    if p.is_symlink() or (p.exists() and not p.is_file()):
        kind = "a symbolic link" if p.is_symlink() else "a folder" if p.is_dir() else "not a regular file"
        raise SolasError(f"{what} {str(path)!r} is {kind}; give a new file name (or a regular file to replace)")
    for source in inputs:
        if source is not None and _same(p, Path(source)):
            raise SolasError(f"{what} {str(path)!r} is an input of this command; give the output another name")
    _writable_folder(p)
    return p


def add_png_option(p) -> None:
    """--png, of every command that writes an OpenEXR image and its PNG preview: where the preview goes.
    The preview is always written (`data_and_preview`); `psf-grid`'s optional mosaic is its --mosaic."""
    p.add_argument(
        "--png",
        metavar="PNG",
        help="where the sRGB PNG preview, always written, goes (default: beside the EXR, of the same name)",
    )


def data_and_preview(
    output: str | os.PathLike, preview: str | os.PathLike | None = None, inputs: Iterable[str | os.PathLike] = ()
) -> tuple[Path, Path]:
    """The checked OpenEXR data path `output` and its PNG preview (default: beside it)."""
    inputs = [i for i in inputs if i is not None]
    data = Path(output)
    if data.suffix.lower() != ".exr":
        hint = f"; write {data.with_suffix('.exr')} (a PNG preview is written beside it)" if data.suffix else ""
        raise SolasError(f"output {str(output)!r} must end in .exr: data is linear OpenEXR{hint}")
    png = Path(preview) if preview is not None else data.with_suffix(".png")
    if png.suffix.lower() != ".png":
        raise SolasError(f"preview {str(png)!r} must end in .png")
    check_target(data, inputs, "output")
    check_target(png, [*inputs, data], "preview")
    return data, png


def output_folder(path: str | os.PathLike) -> Path:
    """A checked output folder: an existing folder or a new name, in a writable place."""
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise SolasError(f"output folder {str(path)!r} exists and is not a folder")
    _writable_folder(p / "x")
    return p


LOCK = ".solas-mi.lock"
# `imageio.atomic_path`'s temporaries: ".NAME.PID.XXXXXXXX.SUFFIX" (mkstemp's 8 characters), nested ones alike
_TEMPORARY = re.compile(r"^\.(?P<name>.+?)(\.\d+)?\.[a-z0-9_]{8}(?P<suffix>\.(exr|png|json))$")


def remove_temporaries(folder: str | os.PathLike) -> int:
    """Remove the hidden temporary files (`imageio.atomic_path`) that a killed writer left in `folder`;
    the number removed. Call it only while holding the folder (`hold_folder`): a live writer's
    temporaries look the same."""
    removed = 0
    for path in Path(folder).iterdir() if Path(folder).is_dir() else ():
        m = _TEMPORARY.match(path.name)
        if m and m["name"].lower().endswith(m["suffix"]) and path.is_file() and not path.is_symlink():
            path.unlink(missing_ok=True)
            removed += 1
    return removed


def _holder(fd: int) -> str:
    os.lseek(fd, 0, os.SEEK_SET)
    return os.read(fd, 512).decode("utf-8", "replace").strip() or "another process"


@contextmanager
def hold_folder(folder: str | os.PathLike, what: str) -> Iterator[Path]:
    """Hold `folder` (created if need be) for the block: its lock file (LOCK, an advisory `flock`,
    released by the system if the process dies) names the holder, `what` with its process id, host
    and start time. SolasError naming the holder when another process holds it. The lock file is
    removed at the end where the folder allows it (the lock is the flock, released in any case)."""
    import fcntl
    import socket
    import time

    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        while True:
            fd = os.open(folder / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = _holder(fd)
                os.close(fd)
                raise SolasError(
                    f"output folder {folder} is in use by {holder}; wait for it to end or give another output folder"
                ) from None
            if os.path.exists(folder / LOCK) and os.stat(folder / LOCK).st_ino == os.fstat(fd).st_ino:
                break
            os.close(fd)  # the holder before removed the file as this process opened it: open it anew
    except OSError as exc:
        raise SolasError(f"cannot hold output folder {folder}: {exc.strerror or exc}") from None
    try:
        os.ftruncate(fd, 0)
        os.write(
            fd,
            f"{what} (process {os.getpid()} on {socket.gethostname()}, since "
            f"{time.strftime('%Y-%m-%dT%H:%M:%S%z')})\n".encode(),
        )
        yield folder
    finally:
        try:
            (folder / LOCK).unlink(missing_ok=True)
        except OSError:  # the folder turned read-only: the file stays, unlocked (the next run takes it)
            pass
        os.close(fd)


@contextmanager
def written_together(*paths: Path) -> Iterator[tuple[str, ...]]:
    """Temporary paths for `paths`, renamed onto them together when the block succeeds; on an error
    or an interruption none of the targets changes and the temporary files are removed. Two processes
    writing the same targets at once: each target ends whole, from the one that renamed last, and the
    renames of each hold their folders (`_renaming`), so a data file and its preview come from one writer."""
    from .imageio import atomic_path

    with ExitStack() as stack:
        held = stack.enter_context(_renaming(Path(p).parent for p in paths))  # released after the renames
        tmps = tuple(stack.enter_context(atomic_path(p)) for p in paths)
        try:
            yield tmps
        except SolasError as exc:  # a failed write names the temporary file: name the target instead
            message = str(exc)
            for tmp, target in zip(tmps, paths):
                message = message.replace(tmp, str(target))
            raise SolasError(message) from None
        held()  # the stack now renames each temporary onto its target, in these folders' hold


@contextmanager
def _renaming(folders: Iterable[Path]) -> Iterator:
    """A function that holds `folders` (an exclusive `flock` on each, in sorted order; no file is made)
    until the block ends; folders that cannot be locked (a file system without locks) are passed over."""
    import fcntl

    fds: list[int] = []

    def hold() -> None:
        for folder in sorted({os.path.abspath(f or ".") for f in folders}):
            try:
                fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
            except OSError:
                continue
            fds.append(fd)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX)
            except OSError:
                pass

    try:
        yield hold
    finally:
        for fd in fds:
            os.close(fd)  # releases its lock
