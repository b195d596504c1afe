"""What the commands share: parsing of command-line values and the option groups several commands take."""
from __future__ import annotations

import re

from .errors import SolasError
from .userfiles import read_toml

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


def parse_size_mm(text: str, what: str) -> tuple[float, float]:
    """"WxH" in mm (e.g. "23.6x15.8") → (width, height): a physical size, unlike `parse_wxh`'s pixel
    counts (which it returns as rows, columns)."""
    parts = str(text).lower().replace("×", "x").split("x")
    try:
        if len(parts) != 2:
            raise ValueError
        return float(parts[0]), float(parts[1])
    except ValueError:
        raise SolasError(f"{what} {text!r} must look like 23.6x15.8 (width x height in mm)") from None


def floats(text: str, what: str) -> list[float]:
    """Comma-separated numbers, at least one."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        values = []
    if not values:
        raise SolasError(f"{what} {text!r} must be one or more comma-separated numbers")
    return values


def positive_ints(text: str, what: str) -> tuple[int, ...]:
    """Comma-separated positive integers, at least one."""
    try:
        values = tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        values = ()
    if not values or min(values) < 1:
        raise SolasError(f"{what} {text!r} must be comma-separated positive integers")
    return values


def add_image_input_options(p, boundaries, variants) -> None:
    """The options of a command that degrades one input image both ways (PSF-grid convolution and
    direct render) and compares them, after its LENS (`optics.commands.add_lens_argument`): IMAGE, -o DIR, --sensor | --scale, --seeds of the
    reference render, --fov-deg, --boundary, --linear, --variant. `boundaries` and `variants` are the
    choices (`optics.camera.BOUNDARIES`, `render.mitsuba.VARIANTS`), given by the caller so that this
    module imports no stage."""
    p.add_argument("image", help="input image, the ideal image spanning ±fov (PNG/JPEG sRGB, EXR linear)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--sensor", help="resample the image to COLSxROWS first (area average); it is the sensor")
    size.add_argument("--scale", type=float, help="resample the image by this factor in (0, 1] first")
    p.add_argument("--seeds", type=int, default=2, help="renders the reference is averaged from (>= 2)")
    p.add_argument("--fov-deg", type=float, help="half the horizontal field the image spans (default: the lens's)")
    p.add_argument("--boundary", choices=boundaries, default="edge", help="padding / object outside the image")
    p.add_argument("--linear", action="store_true", help="PNG/JPEG values are already linear")
    p.add_argument("--variant", choices=variants, help="Mitsuba variant of the render")


def toml_table(path, table: str, what: str) -> dict:
    """The one `[table]` of the TOML file `path` (and nothing else in it), read by `userfiles.read_toml`;
    `what` is its kind there (e.g. "sensor model"), which names the file in the one-line errors."""
    data = read_toml(path, what)
    if not isinstance(data.get(table), dict) or set(data) != {table}:
        raise SolasError(f"{what} {str(path)!r} must hold one [{table}] table (and nothing else); "
                         f"found {', '.join(sorted(data)) or 'nothing'}")
    return data[table]
