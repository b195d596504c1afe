"""Files a user or a file names (`solas_mi.userfiles`): every reader reads regular files only, at most its
kind's bound, never waits on a FIFO nor reads a device, takes only UTF-8 text, refuses TOML nested
deeper than `MAX_NESTING`, and never quotes what a file holds."""

import os
from pathlib import Path

import pytest
from in_time import refused

from solas_mi import userfiles
from solas_mi.userfiles import LIMITS, MAX_NESTING, check, read_bytes, read_text, read_toml


@pytest.fixture
def odd(tmp_path):
    """Paths that are no regular file: a FIFO, /dev/zero, a symbolic link to it, a folder."""
    os.mkfifo(tmp_path / "fifo")
    os.symlink("/dev/zero", tmp_path / "zero")
    (tmp_path / "folder").mkdir()
    return tmp_path


@pytest.mark.parametrize(
    "name, why",
    [
        ("fifo", "is not a regular file"),
        ("zero", "is not a regular file"),
        ("/dev/zero", "is not a regular file"),
        ("folder", "is a folder"),
        ("missing", "does not exist"),
    ],
)
@pytest.mark.parametrize("reader", [check, read_bytes, read_text, read_toml])
def test_only_regular_files_are_read(odd, name, why, reader):
    path = odd / name
    message = refused(reader, path, "lens file")
    assert why in message and repr(str(path)) in message


def test_the_bound_of_each_kind_is_stated_and_holds(tmp_path, monkeypatch):
    """A file of exactly its kind's bound is read, one byte more is refused naming the bound; a sparse file
    of any size is refused from its size alone; a file that reports no size (/proc) is read to the bound
    and no further."""
    for kind, limit in LIMITS.items():
        big = tmp_path / "big"
        with open(big, "wb") as f:
            f.truncate(limit + 1)  # sparse: no disk used
        assert f"is larger than {userfiles._size(limit)}, the most" in refused(check, big, kind)
    monkeypatch.setitem(LIMITS, "lens file", 10)
    (tmp_path / "ten").write_bytes(b"0123456789")
    (tmp_path / "eleven").write_bytes(b"0123456789a")
    assert read_bytes(tmp_path / "ten", "lens file") == b"0123456789"
    assert "larger than 10 bytes" in refused(read_bytes, tmp_path / "eleven", "lens file")
    assert os.stat("/proc/self/environ").st_size == 0 and len(os.environ.get("PATH", "")) > 10
    assert "larger than 10 bytes" in refused(read_bytes, "/proc/self/environ", "lens file")


@pytest.mark.parametrize(
    "data, why",
    [
        (b"a = 1\x00\n", "it holds NUL bytes"),
        ("a = 'caf\xe9'\n".encode("latin-1"), "byte 9 is not UTF-8"),
        ("a = 1\n".encode("utf-16"), "it holds NUL bytes"),
        (b"\x89PNG\r\n\x1a\n", "byte 1 is not UTF-8"),
    ],
)
def test_text_is_utf8(tmp_path, data, why):
    path = tmp_path / "t.toml"
    path.write_bytes(data)
    message = refused(read_toml, path, "sensor model")
    assert f"is not UTF-8 text ({why}" in message and "a sensor model is UTF-8 text" in message
    path.write_bytes(b"\xef\xbb\xbfa = 1\n")  # a byte-order mark is UTF-8 still
    assert read_toml(path, "sensor model") == {"a": 1}


def test_nothing_of_a_file_is_quoted(tmp_path):
    """The process environment (/proc/self/environ) and a file of secrets read as TOML: refused without
    a word of them."""
    environment = [v for v in os.environ.values() if len(v) > 3]
    message = refused(read_toml, "/proc/self/environ", "sensor model")
    assert environment and not any(v in message for v in environment)
    (tmp_path / "secret").write_text("SECRET hunter2\n")
    assert "hunter2" not in refused(read_toml, tmp_path / "secret", "isp file")


def test_nesting_is_bounded(tmp_path):
    """`x` nested in arrays: the root table and MAX_NESTING - 1 arrays are read, one more is refused,
    and so are thousands (which Python's TOML parser cannot read: RecursionError)."""
    path = tmp_path / "deep.toml"
    for arrays, ok in ((MAX_NESTING - 1, True), (MAX_NESTING, False), (3000, False)):
        path.write_text("x = " + "[" * arrays + "1" + "]" * arrays + "\n")
        if ok:
            assert read_toml(path, "lens file")["x"]
        else:
            assert f"nests tables and arrays more than {MAX_NESTING} levels deep" in refused(
                read_toml, path, "lens file"
            )


def test_the_docs_state_the_bounds():
    """The conventions page states each kind's bound and the nesting as `LIMITS` and `MAX_NESTING` hold them."""
    text = " ".join((Path(__file__).resolve().parents[1] / "docs" / "conventions.md").read_text().split())
    assert all(f"{kind} {userfiles._size(limit)}" in text for kind, limit in LIMITS.items())
    assert f"a TOML file nests at most {MAX_NESTING} levels" in text
