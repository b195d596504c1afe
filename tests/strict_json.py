"""JSON as a strict reader (JavaScript's JSON.parse, Go, serde) reads it: the bare tokens Python's json
writes for non-finite floats (Infinity, -Infinity, NaN) are refused, as those readers refuse the file."""

import json


def _refuse(token: str):
    raise ValueError(f"{token} is not JSON")


def strict_loads(text: str | bytes):
    """`text` parsed as strict JSON; ValueError at a NaN/Infinity token."""
    return json.loads(text, parse_constant=_refuse)


def exr_meta(path) -> dict:
    """The solas-mi metadata of an EXR file as its header holds it, parsed strictly."""
    import OpenEXR

    from solas_mi.imageio import META_KEY

    with OpenEXR.File(str(path)) as f:
        return strict_loads(f.header()[META_KEY])
