"""What the commands share: parsing of command-line values and the option groups several commands take."""
from __future__ import annotations

import re

from .errors import SolasError

_WXH = re.compile(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*")


def parse_wxh(text: str | tuple[int, int], what: str, minimum: int = 1) -> tuple[int, int]:
    """"WxH" (columns × rows, e.g. "32x24") or a (rows, columns) tuple → (rows, columns), each ≥ `minimum`."""
    if isinstance(text, tuple):
        rows, cols = text
        ok = all(isinstance(v, int) and not isinstance(v, bool) for v in text)
    else:
        m = _WXH.fullmatch(str(text))
        ok = m is not None
        rows, cols = (int(m.group(2)), int(m.group(1))) if m else (0, 0)
    if not ok or rows < minimum or cols < minimum:
        raise SolasError(f"{what} {text!r} must look like 32x24 (columns x rows), each >= {minimum}")
    return rows, cols


def floats(text: str, what: str) -> list[float]:
    """Comma-separated numbers."""
    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise SolasError(f"{what} {text!r} must be comma-separated numbers") from None


def add_lens_argument(p) -> None:
    """The positional LENS argument of every command that takes a lens."""
    p.add_argument("lens", help="shipped lens name (solas-doublet, cooke-triplet) or a .toml lens file")
