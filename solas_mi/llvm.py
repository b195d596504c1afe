"""Selection of a libLLVM that Dr.Jit's LLVM backend can use, before drjit is imported.

Dr.Jit crashes with libLLVM 15 and 16 and rejects 14, so only 17 or newer is accepted.
"""

from __future__ import annotations

import glob
import os
import re
from pathlib import Path

from .errors import SolasError

MIN_VERSION = 17
_SEARCH = (
    "/usr/lib/x86_64-linux-gnu/libLLVM*.so*",
    "/usr/lib/aarch64-linux-gnu/libLLVM*.so*",
    "/usr/lib/llvm-*/lib/libLLVM*.so*",
    "/usr/lib64/libLLVM*.so*",
    "/usr/local/lib/libLLVM*.so*",
    "/opt/homebrew/opt/llvm/lib/libLLVM*.dylib",
    "/usr/local/opt/llvm/lib/libLLVM*.dylib",
)


def libllvm_version(path: str) -> int | None:
    """Major version of a libLLVM: from its folder (/usr/lib/llvm-19/lib/libLLVM.so.1) or else its
    file name (libLLVM-19.so, libLLVM.so.19.1)."""
    name = Path(path).name
    m = re.search(r"llvm-(\d+)/", path) or re.search(r"libLLVM-(\d+)", name) or re.search(r"\.so\.(\d+)", name)
    return int(m.group(1)) if m else None


def find_libllvm() -> tuple[str | None, list[tuple[int, str]]]:
    """Newest usable libLLVM (≥ 17) on this machine, and every version found."""
    found: list[tuple[int, str]] = []
    for pattern in _SEARCH:
        for path in sorted(glob.glob(pattern)):
            version = libllvm_version(path)
            if version is not None and os.path.isfile(path):
                found.append((version, path))
    usable = sorted((v, p) for v, p in found if v >= MIN_VERSION)
    return (usable[-1][1] if usable else None), found


def select_libllvm() -> str:
    """Point DRJIT_LIBLLVM_PATH at a usable libLLVM; raise SolasError when none exists."""
    chosen = os.environ.get("DRJIT_LIBLLVM_PATH")
    if chosen:
        version = libllvm_version(chosen)
        if not os.path.isfile(chosen):
            raise SolasError(f"DRJIT_LIBLLVM_PATH={chosen!r} does not exist")
        if version is not None and version < MIN_VERSION:
            raise SolasError(
                f"DRJIT_LIBLLVM_PATH={chosen!r} is libLLVM {version}; Dr.Jit needs libLLVM >= {MIN_VERSION}"
            )
        return chosen
    chosen, found = find_libllvm()
    if chosen is None:
        seen = ", ".join(f"{v} ({p})" for v, p in found) or "none"
        raise SolasError(
            f"Dr.Jit needs libLLVM >= {MIN_VERSION}; found: {seen}. "
            "Install one (Debian: apt-get install -y libllvm19) or set DRJIT_LIBLLVM_PATH."
        )
    os.environ["DRJIT_LIBLLVM_PATH"] = chosen
    return chosen


def import_drjit():
    """Import drjit after selecting libLLVM; returns the drjit module."""
    select_libllvm()
    import drjit

    return drjit
