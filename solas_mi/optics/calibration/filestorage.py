"""OpenCV FileStorage files (YAML `%YAML:1.0` and JSON) and Kalibr camera chains (plain YAML), written and
read without OpenCV: the shapes of cv::FileStorage's documents (maps, flow sequences, `!!opencv-matrix`
maps of rows, cols, dt, data; JSON matrices as maps with "type_id": "opencv-matrix").

`dumps_yaml(document)` / `dumps_json(document)` write a document (a dict of numbers, strings, lists,
`Matrix` values and nested dicts; floats in full, so they read back bit for bit); `loads(text, where)`
reads either form back into the same dict (matrices as `Matrix`). Numbers that are not finite are written
as strings ("inf"), as JSON has no infinity.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass

from ...errors import SolasError

_KEY = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_NUMBER = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\Z")


@dataclass(frozen=True)
class Matrix:
    """An OpenCV matrix of doubles: rows × cols values, row-major."""

    rows: int
    cols: int
    data: tuple[float, ...]

    def row(self) -> list[float]:
        return list(self.data)


def _plain(value):
    """A value as JSON data: non-finite numbers as text, tuples as lists."""
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return None if value is None else value


def _scalar(value) -> str:
    value = _plain(value)
    if isinstance(value, bool):
        return str(int(value))
    if isinstance(value, (int, float)):
        return repr(value)
    return json.dumps("none" if value is None else str(value), ensure_ascii=False)


def _yaml_lines(document: dict, indent: int) -> list[str]:
    pad, out = " " * indent, []
    for key, value in document.items():
        if not _KEY.match(key):
            raise SolasError(f"FileStorage key {key!r} must be letters, digits and underscores")
        if isinstance(value, Matrix):
            data = ", ".join(repr(float(v)) for v in value.data)
            out += [
                f"{pad}{key}: !!opencv-matrix",
                f"{pad}   rows: {value.rows}",
                f"{pad}   cols: {value.cols}",
                f"{pad}   dt: d",
                f"{pad}   data: [ {data} ]",
            ]
        elif isinstance(value, dict):
            out += [f"{pad}{key}:", *_yaml_lines(value, indent + 3)]
        elif isinstance(value, (list, tuple)):
            out.append(f"{pad}{key}: [ {', '.join(_scalar(v) for v in value)} ]")
        else:
            out.append(f"{pad}{key}: {_scalar(value)}")
    return out


def dumps_yaml(document: dict, header: str = "%YAML:1.0\n---") -> str:
    """A FileStorage YAML file (header "" and no matrices: a plain YAML map, as Kalibr's camera chains)."""
    return "\n".join(([header] if header else []) + _yaml_lines(document, 0)) + "\n"


def dumps_json(document: dict) -> str:
    """A FileStorage JSON file."""

    def convert(value):
        if isinstance(value, Matrix):
            return {
                "type_id": "opencv-matrix",
                "rows": value.rows,
                "cols": value.cols,
                "dt": "d",
                "data": [float(v) for v in value.data],
            }
        if isinstance(value, dict):
            return {k: convert(v) for k, v in value.items()}
        return _plain(value)

    return json.dumps(convert(document), indent=4, ensure_ascii=False, allow_nan=False) + "\n"


def _value(text: str, where: str):
    text = text.strip()
    if text.startswith("["):
        if not text.endswith("]"):
            raise SolasError(f"{where}: a sequence has no closing ]")
        inner = text[1:-1].strip()
        return [_value(t, where) for t in _split(inner)] if inner else []
    if text[:1] in "\"'":
        return text[1:-1]
    if _NUMBER.match(text):
        return int(text) if re.fullmatch(r"[-+]?\d+", text) else float(text)
    return text


def _split(text: str) -> list[str]:
    """Items of a flow sequence's inside, commas inside quotes or brackets kept."""
    items, depth, quote, start = [], 0, "", 0
    for i, ch in enumerate(text):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch == "[":
            depth += 1
        elif ch == "]":
            depth -= 1
        elif ch == "," and depth == 0:
            items.append(text[start:i])
            start = i + 1
    return items + [text[start:]]


def _joined(text: str) -> list[str]:
    """The document's lines, a flow sequence continued over several lines joined into one."""
    lines, held = [], ""
    for raw in text.splitlines():
        stripped = raw.strip()
        if not held and (not stripped or stripped.startswith(("%", "#")) or stripped == "---"):
            continue
        held = f"{held} {stripped}" if held else raw.rstrip()
        if held.count("[") <= held.count("]"):
            lines.append(held)
            held = ""
    return lines + ([held] if held else [])


def _matrices(value):
    if isinstance(value, dict):
        if value.get("type_id") == "opencv-matrix" or {"rows", "cols", "data"} <= set(value):
            return Matrix(int(value["rows"]), int(value["cols"]), tuple(float(v) for v in value["data"]))
        return {k: _matrices(v) for k, v in value.items()}
    return value


def loads(text: str, where: str) -> dict:
    """A FileStorage (YAML or JSON) or plain YAML map's document; SolasError naming `where` if it is neither."""
    if text.lstrip().startswith("{"):
        try:
            return _matrices(json.loads(text))
        except json.JSONDecodeError as exc:
            raise SolasError(f"{where}: not a JSON document ({exc.msg} at line {exc.lineno})") from None
    root: dict = {}
    stack = [(-1, root)]
    for number, line in enumerate(_joined(text), 1):
        indent = len(line) - len(line.lstrip())
        key, colon, rest = line.strip().partition(":")
        if not colon or not key or key.startswith("-"):
            raise SolasError(f"{where}: entry {number} is not a `key: value` of a FileStorage map")
        while stack[-1][0] >= indent:
            stack.pop()
        rest = rest.strip()
        if rest == "" or rest.startswith("!!opencv-matrix"):
            child: dict = {"type_id": "opencv-matrix"} if rest else {}
            stack[-1][1][key.strip()] = child
            stack.append((indent, child))
        else:
            stack[-1][1][key.strip()] = _value(rest, where)
    return _matrices(root)
