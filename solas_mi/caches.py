"""Where solas-mi keeps what it computed once and reuses: `cache_root`, the folder of its caches (the PSF grids
of `batch.cache`, the fitted cameras of `optics.calibration`), `RecordCache`, JSON records kept by a key, and
`FileCache`, files (the ghost grids of `psf.ghost_nodes`) kept by a key with a record of it beside each, and
`parsed_files`, what parsing some files gives (the shipped glass catalogue of `optics.glass`) kept by their contents.

The root is $SOLAS_MI_CACHE_DIR where set (`ENV`), else the user's cache directory (`platformdirs`), e.g.
~/.cache/solas-mi. A record is a file named by the hash of its key, holding its key, its value and the value's
SHA-256; it is reused only when all three match, so a corrupt, truncated, foreign or unreadable record is said
so on stderr and computed again, never trusted and never an error. A folder that cannot be written is no
error either: the value is computed each time, and stderr says so once.
"""

from __future__ import annotations

import hashlib
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, ClassVar

from . import jsonio
from .errors import SolasError

ENV = "SOLAS_MI_CACHE_DIR"  # the environment variable that moves every cache of solas-mi


def cache_root() -> Path:
    """The folder of solas-mi's caches: $SOLAS_MI_CACHE_DIR where set, else the user's cache directory."""
    chosen = os.environ.get(ENV)
    if chosen:
        return Path(chosen).expanduser()
    from platformdirs import user_cache_dir

    return Path(user_cache_dir("solas-mi"))


def file_hash(path: str | os.PathLike, full: bool = False) -> str:
    """The first 16 hex digits of the file's SHA-256 (all 64 when `full`)."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest() if full else digest.hexdigest()[:16]


def _digest(value: Any) -> str:
    return hashlib.sha256(jsonio.dumps(value, sort_keys=True).encode()).hexdigest()


class RecordCache:
    """JSON values kept in a folder of `cache_root` by their key (module docstring).

    Parameters
    ----------
    name : str
        The folder's name in `cache_root()` (read when a record is looked up: $SOLAS_MI_CACHE_DIR may change).
    what : str
        What a record holds, as the notes on stderr call it ("camera fit").

    Examples
    --------
    >>> squares = RecordCache("squares", "square")
    >>> squares.path({"n": 3}).parent == cache_root() / "squares"  # squares.get({"n": 3}, lambda: 9) keeps 9 there
    True
    """

    unwritable: ClassVar[set[Path]] = set()  # folders already said to be unwritable, in this process

    def __init__(self, name: str, what: str):
        self.name = name
        self.what = what

    def not_kept(self, folder: Path, exc: SolasError) -> None:
        """Say once per folder on stderr that what cannot be written there is computed each time."""
        if folder not in self.unwritable:
            self.unwritable.add(folder)
            print(
                f"{exc}: the {self.what} is not kept, computed each time (set {ENV} to a folder you can write)",
                file=sys.stderr,
                flush=True,
            )

    def path(self, key: Any) -> Path:
        """The file of the record of `key`: its hash's first 32 hex digits, in the folder."""
        return cache_root() / self.name / f"{_digest(key)[:32]}.json"

    def read(self, path: Path, key: Any) -> tuple[Any, str | None]:
        """The value of the record `path` of `key`, and None; or None and why it is not reused."""
        from .userfiles import read_text

        try:
            record = jsonio.loads(read_text(path, "record"))
        except (OSError, ValueError) as exc:  # SolasError is a ValueError: unreadable, too large, not JSON
            return None, f"it cannot be read as JSON ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})"
        if not isinstance(record, dict) or set(record) != {"key", "value", "sha256"}:
            return None, "it is not a record of this cache"
        if record["key"] != jsonio.loads(jsonio.dumps(key)):
            return None, "its record names another key"
        if record["sha256"] != _digest(record["value"]):
            return None, "its value does not match its checksum (changed or truncated)"
        return record["value"], None

    def holds(self, key: Any) -> bool:
        """Whether the record of `key` is there and whole (`get` would read it back)."""
        path = self.path(key)
        return path.exists() and self.read(path, key)[1] is None

    def get(self, key: Any, compute: Callable[[], Any]) -> tuple[Any, bool]:
        """The value of `key` (JSON values): read back where its record is whole, else `compute()`d and kept.

        Returns
        -------
        tuple
            (the value, as JSON reads it back; whether it came from the cache).
        """
        from .imageio import write_text

        path = self.path(key)
        if path.exists():
            value, why = self.read(path, key)
            if why is None:
                return value, True
            print(
                f"cache entry {path} is not reused: {why}; computing the {self.what} again", file=sys.stderr, flush=True
            )
        value = jsonio.loads(jsonio.dumps(compute()))  # as a read-back gives it: a first run and a second agree
        try:
            write_text(path, jsonio.dumps({"key": key, "value": value, "sha256": _digest(value)}, indent=1) + "\n")
        except SolasError as exc:
            self.not_kept(path.parent, exc)
        return value, False


class FileCache(RecordCache):
    """Files kept in a folder of `cache_root` by their key, each with its record beside it (``NAME.json``: the
    key and the file's SHA-256); an entry is reused only when its record names the key and the file's content
    matches, so a changed, swapped or truncated file is said so on stderr and computed again.

    Parameters
    ----------
    name : str
        The folder's name in `cache_root()`.
    what : str
        What a file holds, as the notes on stderr call it ("ghost grid").
    suffix : str
        The files' ending (".exr").
    """

    def __init__(self, name: str, what: str, suffix: str):
        super().__init__(name, what)
        self.suffix = suffix

    def path(self, key: Any) -> Path:
        """The file of `key`: its hash's first 32 hex digits, in the folder."""
        return super().path(key).with_suffix(self.suffix)

    def check(self, path: Path, key: Any) -> str | None:
        """None where `path` is whole and its record names `key`; else why it is not reused."""
        value, why = self.read(Path(f"{path}.json"), key)
        if why is not None:
            return f"its record: {why}"
        return None if value == file_hash(path, full=True) else "its content does not match its record's checksum"

    def get_file(self, key: Any, compute: Callable[[], Any], write: Callable, read: Callable) -> tuple[Any, bool]:
        """The value of `key`: ``read(path)`` where its file is whole, else ``compute()``d, kept by ``write(value,
        path)`` (atomic) with its record and read back; a folder that cannot be written: computed each time.

        Returns
        -------
        tuple
            (the value; whether it came from the cache).
        """
        from .imageio import write_text

        path = self.path(key)
        if path.exists():
            why = self.check(path, key)
            if why is None:
                return read(path), True
            print(f"cache entry {path} is not reused: {why}; computing the {self.what} again", file=sys.stderr)
        value = compute()
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            write(value, path)
            digest = file_hash(path, full=True)
            write_text(f"{path}.json", jsonio.dumps({"key": key, "value": digest, "sha256": _digest(digest)}) + "\n")
            return read(path), False  # as a read-back gives it: a first call and a second agree
        except OSError as exc:
            self.not_kept(path.parent, SolasError(f"cannot write {path}: {exc.strerror or exc}"))
        except SolasError as exc:
            self.not_kept(path.parent, exc)
        return value, False


def parsed_files(name: str, what: str, files: list[Path], parse: Callable[[], Any]) -> Any:
    """`parse()`, the plain Python values (dicts, lists, strings, numbers) that `files` hold, kept in the folder
    `name` of `cache_root` by the files' contents as a `marshal` file, checked by its record as every `FileCache`
    file is: read back in milliseconds where parsing took a tenth of a second (the shipped glass catalogue's TOML,
    on every start of a process that loads a lens). `what` names it in the notes on stderr."""
    import marshal

    key = {
        "files": [[p.name, file_hash(p, full=True)] for p in files],
        "marshal": [marshal.version, *sys.version_info[:2]],
    }

    def write(value: Any, path: Path) -> None:
        from .imageio import atomic_path

        with atomic_path(path) as tmp:
            Path(tmp).write_bytes(marshal.dumps(value))

    cache = FileCache(name, what, ".marshal")
    return cache.get_file(key, parse, write, lambda path: marshal.loads(path.read_bytes()))[0]
