"""JSON as every reader parses it: the metadata, manifests, records and `--json` outputs solas-mi writes.

Python's `json` writes an infinite float as the bare token `Infinity` (NaN as `NaN`), which is not
JSON: JavaScript's `JSON.parse`, Go, Rust's serde, jq and most other loaders refuse the whole file.
Here (`dumps`) an infinity is written as the string "inf" ("-inf" below zero), the form the files
already used for infinite distances (`distances_m`, `focus_distance`): Python's `float`, Go's
`strconv.ParseFloat`, Rust's `str::parse::<f64>` and C's `strtod` read it as infinity; JavaScript
and Java need `v === "inf" ? Infinity : v`. A NaN is never written: it is a SolasError naming the
key (a NaN in the results is a wrong answer upstream, not something to store).

`loads` reads these files and the ones written before, whose `Infinity` tokens it reads as "inf",
so that an old file and a new one read the same (resumed batches, cache records, reused references);
an old `NaN` token reads as a float NaN.
"""

from __future__ import annotations

import json
import math
import numbers
from typing import Any

from .errors import SolasError

INFINITY = "inf"  # how an infinite number is written; "-inf" below zero
_OLD_TOKENS = {"Infinity": INFINITY, "-Infinity": "-" + INFINITY, "NaN": math.nan}


def _plain(value: Any, where: str = "") -> Any:
    """`value` with every infinite number (Python or NumPy float, in dicts, lists and tuples) as "inf"
    or "-inf" and NumPy numbers as Python ones; SolasError naming the key of a NaN (`where`: the
    path so far)."""
    if isinstance(value, dict):
        return {k: _plain(v, f"{where}.{k}" if where else str(k)) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, numbers.Integral) and not isinstance(value, int):
        return int(value)  # a NumPy integer
    if isinstance(value, numbers.Real) and not isinstance(value, int):
        number = float(value)
        if math.isnan(number):
            raise SolasError(
                f"{where or 'value'} is NaN (not a number), which JSON cannot hold and solas-mi "
                "does not write: a result came out undefined"
            )
        if math.isinf(number):
            return INFINITY if number > 0 else "-" + INFINITY
        return value if isinstance(value, float) else number
    return value


def dumps(value: Any, **options) -> str:
    """`value` as strict JSON text (`json.dumps` `options`: indent, sort_keys, default …): infinities
    as "inf"/"-inf", NumPy numbers as numbers, SolasError naming the key of a NaN."""
    return json.dumps(_plain(value), allow_nan=False, **options)


def loads(text: str | bytes) -> Any:
    """JSON text as Python values, the old tokens `Infinity`/`-Infinity` as "inf"/"-inf" (as written now);
    SolasError (a ValueError, as `json`'s own errors) for arrays or objects nested deeper than Python's
    parser goes."""
    try:
        return json.loads(text, parse_constant=_OLD_TOKENS.__getitem__)
    except RecursionError:
        raise SolasError(
            "JSON nested deeper than the parser goes (thousands of levels): not a file solas-mi wrote"
        ) from None
