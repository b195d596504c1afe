"""The kinds of label a frame carries beside its image (`KINDS`, a `solas_mi.registry.Registry`), read by
every stage: the render traces some of them through the lens (`render.labels.LABELS`), `degrade` warps
each of them with the frame (`convolution.labels`), a batch never takes their files for frames
(`batch.jobs.label_layer`).

An entry: its function reads one file of the kind, `(path) ->` the values as an H×W×C float64 array of
its `layers` (EXR channel names: as `render --labels` writes them and `degrade --labels` reads and writes
them), or for a JSON kind the annotations, checked; `files`: the file types it is read from; `rule`: how
it follows the lens's mapping (`RULES`, applied by `convolution.labels`). Bad values are refused by name
(an id that is not a whole number, a NaN, a negative depth), never repaired.

Coordinates: an image label's pixel (column, row) as the frame's; optical flow in pixels, +x along the
columns (right), +y along the rows (down), as Middlebury, KITTI and Sintel store it; the JSON kind's
points as COCO's, (x, y) from the image's top-left corner (the first pixel spans 0 … 1).

This module imports nothing heavy when loaded: the readers load NumPy and the image readers when called.
"""

from __future__ import annotations

import math
from typing import Any

from .errors import SolasError
from .registry import Registry

VALID = "labels.valid"  # the layer written beside every label: 1 where the label holds
ID_LIMIT = 1 << 24  # ids below 2^24 are exact in a float32 channel
# the flare label a frame with stray light carries (render --ghosts, degrade --ghosts): the stray light's irradiance
# per pixel (the channels' mean, the image's units) and its ratio to the direct image's (the same mean), 0 where no
# stray light arrives, MAX_RATIO where it meets a pixel the direct image leaves dark; never NaN (`flare_layers`)
FLARE_LAYERS = ("flare.irradiance", "flare.ratio")
MAX_RATIO = 1e6
# how a kind follows a warp of its frame, by name (`convolution.labels` applies each)
RULES = {
    "pick": "the value of one of the four pixels around the source point, never blended (no value appears that was "
    "not in the input): each with the probability of its bilinear weight, by a fixed dither, so that an edge "
    "moves by the sub-pixel part of its shift (rounding would move it by whole pixels)",
    "surface": "interpolated bilinearly between the four pixels around the source point where they lie on one "
    "surface (depths apart by less than a silhouette, `convolution.depth.SILHOUETTE_RATIO`), else picked as "
    "ids are; the value itself is kept",
    "flow": "picked as ids are, its end point moved by the same mapping: the value is the moved end point minus "
    "the moved start point",
    "points": "each point moved by the mapping; a box is the bounding box of its moved outline",
}
_ANNOTATIONS = "annotations file"


def _channels(names: list[str], kind: str, path) -> list[str]:
    """The channels of an EXR file holding `kind`: its layers (`depth.Z`), else the first of its spellings
    found, else the only channel of a one-layer kind; SolasError naming the channels otherwise."""
    entry = KINDS[kind]
    for spelling in (entry.extra["layers"], *entry.extra["spellings"]):
        if all(n in names for n in spelling):
            return list(spelling)
    if len(entry.extra["layers"]) == 1 and len(names) == 1:
        return names
    ways = " or ".join(", ".join(s) for s in (entry.extra["layers"], *entry.extra["spellings"]))
    raise SolasError(
        f"{kind} labels {str(path)!r} have channels {', '.join(names)}: they must be {ways}"
        f"{' (or the only channel)' if len(entry.extra['layers']) == 1 else ''}"
    )


def read_layers(path, kind: str):
    """The values (H, W, C) float64 of the `kind` label file `path`: an EXR's channels (`_channels`), or
    the integers a PNG/TIFF stores (one channel; three equal channels read as one)."""
    import numpy as np

    from .imageio import read_exr, read_stored
    from .userfiles import check

    entry = KINDS[kind]
    path = check(path, "image file")
    if path.suffix.lower() not in entry.extra["files"]:
        raise SolasError(f"{kind} labels {str(path)!r} must be a {' or '.join(entry.extra['files'])} file")
    if path.suffix.lower() == ".exr":
        channels, _ = read_exr(path)
        values = np.stack([channels[n] for n in _channels(list(channels), kind, path)], axis=-1)
    else:
        values = read_stored(path)
        values = values[..., None] if values.ndim == 2 else values
        if values.shape[-1] in (2, 4):  # an alpha channel
            values = values[..., :-1]
        if values.shape[-1] == 3 and (values == values[..., :1]).all():
            values = values[..., :1]
        if values.shape[-1] != 1:
            raise SolasError(
                f"{kind} labels {str(path)!r} have {values.shape[-1]} different channels: one channel "
                "of ids is read (colour-coded ids are not)"
            )
    values = values.astype(np.float64)
    entry.extra["check"](values, path)
    return values


def _first(bad, values, path, kind: str, allowed: str) -> None:
    """SolasError naming the first value where `bad` holds, its place and what is allowed (nothing if none)."""
    import numpy as np

    if bad.any():
        r, c, k = np.argwhere(bad)[0]
        raise SolasError(
            f"{kind} labels {str(path)!r}: value {float(values[r, c, k])!r} at row {r}, column {c} "
            f"({int(bad.sum())} such values): {allowed}"
        )


def _ids(kind: str):
    def check(values, path) -> None:
        import numpy as np

        with np.errstate(invalid="ignore"):
            _first(
                ~np.isfinite(values) | (values != np.round(values)) | (values < 0) | (values >= ID_LIMIT),
                values,
                path,
                kind,
                f"{kind} ids are whole numbers from 0 to {ID_LIMIT - 1} (a float or blended id "
                "belongs to no object: give the ids as written)",
            )

    return check


def _depth_values(values, path) -> None:
    import numpy as np

    with np.errstate(invalid="ignore"):
        _first(
            np.isnan(values) | (values < 0),
            values,
            path,
            "depth",
            "depths are metres >= 0 (0: nothing met), inf for the sky",
        )


def _finite(kind: str):
    def check(values, path) -> None:
        import numpy as np

        _first(~np.isfinite(values), values, path, kind, f"{kind} values must be finite")

    return check


def _numbers(value, count: int | None) -> bool:
    return (
        isinstance(value, list)
        and (count is None or len(value) == count)
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)
    )


def read_annotations(path, kind: str = "boxes") -> dict[str, Any]:
    """The annotations file `path`: a JSON object whose "annotations" is a list of objects, each with
    any of "bbox" ([x, y, w, h], COCO's: w, h >= 0), "keypoints" ([x1, y1, v1, x2, y2, v2, ...], COCO's
    visibility v: 0 not labelled, 1 hidden, 2 visible) and "segmentation" (COCO polygons [[x1, y1, x2,
    y2, ...], ...]); every other key is kept as it is. SolasError naming the annotation and the key."""
    from . import jsonio
    from .userfiles import read_text

    try:
        data = jsonio.loads(read_text(path, _ANNOTATIONS))
    except ValueError as exc:
        raise SolasError(f"{kind} file {str(path)!r} is not JSON ({str(exc).splitlines()[0]})") from None
    if not isinstance(data, dict) or not isinstance(data.get("annotations"), list):
        raise SolasError(
            f'{kind} file {str(path)!r} must be a JSON object whose "annotations" is a list (COCO\'s layout)'
        )
    for i, a in enumerate(data["annotations"]):
        bad = None if isinstance(a, dict) else "is not an object"
        if bad is None and "bbox" in a and not (_numbers(a["bbox"], 4) and min(a["bbox"][2:]) >= 0):
            bad = "has a bbox that is not [x, y, w, h] (4 finite numbers, w and h >= 0)"
        points = a.get("keypoints") if bad is None else None
        if points is not None and not (_numbers(points, None) and len(points) % 3 == 0):
            bad = "has keypoints that are not [x1, y1, v1, x2, y2, v2, ...] (finite numbers, in threes)"
        shapes = a.get("segmentation") if bad is None else None
        if shapes is not None and not (
            isinstance(shapes, list) and all(_numbers(s, None) and len(s) % 2 == 0 for s in shapes)
        ):
            bad = (
                "has a segmentation that is not a list of polygons [x1, y1, x2, y2, ...] (run-length "
                "encoded masks: give the mask as a label image)"
            )
        if bad:
            raise SolasError(f"{kind} file {str(path)!r}: annotation {i} {bad}")
    return data


KINDS = Registry("label kind", shown=("layers", "files", "rule"))
_EXR, _IDS = (".exr",), (".png", ".tif", ".tiff", ".exr")
KINDS.register(
    "depth",
    lambda path: read_layers(path, "depth"),
    layers=("depth.Z",),
    spellings=(("Z",), ("depth",), ("Y",)),
    files=_EXR,
    rule="surface",
    check=_depth_values,
    summary="distance in metres, along the optical axis (degrade --depth's maps) or a range from the "
    "projection centre (render's); 0 where nothing is met, inf for the sky",
)
KINDS.register(
    "normal",
    lambda path: read_layers(path, "normal"),
    layers=("normal.X", "normal.Y", "normal.Z"),
    spellings=(("X", "Y", "Z"), ("R", "G", "B")),
    files=_EXR,
    rule="pick",
    check=_finite("normal"),
    summary="the surface's unit normal, in the world's or the camera's frame",
)
KINDS.register(
    "instance",
    lambda path: read_layers(path, "instance"),
    layers=("instance.id",),
    spellings=(("id",), ("Y",)),
    files=_IDS,
    rule="pick",
    check=_ids("instance"),
    summary="an object's id, a whole number (0: background)",
)
KINDS.register(
    "semantic",
    lambda path: read_layers(path, "semantic"),
    layers=("semantic.id",),
    spellings=(("id",), ("Y",)),
    files=_IDS,
    rule="pick",
    check=_ids("semantic"),
    summary="a class id, a whole number",
)
KINDS.register(
    "mask",
    lambda path: read_layers(path, "mask"),
    layers=("mask.Y",),
    spellings=(("Y",),),
    files=_IDS,
    rule="pick",
    check=_ids("mask"),
    summary="a mask of whole numbers (0 and 1, or 0 and 255)",
)
KINDS.register(
    "flow",
    lambda path: read_layers(path, "flow"),
    layers=("flow.X", "flow.Y"),
    spellings=(("X", "Y"), ("U", "V"), ("R", "G")),
    files=_EXR,
    rule="flow",
    check=_finite("flow"),
    summary="optical flow to the next frame, pixels: +x right, +y down",
)
KINDS.register(
    "boxes",
    read_annotations,
    layers=(),
    spellings=(),
    files=(".json",),
    rule="points",
    summary="2D boxes, keypoints and polygons of objects, COCO's JSON layout",
)


def kinds_help() -> str:
    """The kinds and the files each is read from, for help texts: "depth .exr, ..., boxes .json"."""
    return ", ".join(f"{kind} {'/'.join(KINDS[kind].extra['files'])}" for kind in KINDS)


def parse_label_files(text, what: str, pattern: bool = False) -> tuple[tuple[str, str], ...]:
    """The (kind, file) pairs of "KIND=FILE[,KIND=FILE...]" (or of a dict or pairs), each kind of `KINDS`
    once and its file of the kind's type; with `pattern`, each file a name holding {stem} (the frame's
    name without its suffix), beside the frame. SolasError naming the bad part and what is allowed."""
    if isinstance(text, str):
        parts = [p.strip() for p in text.split(",") if p.strip()]
        pairs = [tuple(s.strip() for s in p.partition("=")[::2]) if "=" in p else (p, "") for p in parts]
    else:
        pairs = list(text.items() if isinstance(text, dict) else text or ())
    if not pairs:
        raise SolasError(f"{what} {text!r} must be KIND=FILE[,KIND=FILE...], KIND one of {', '.join(KINDS)}")
    out: dict[str, str] = {}
    for pair in pairs:
        kind, name = pair if isinstance(pair, tuple) and len(pair) == 2 else (pair, "")
        if kind not in KINDS or not isinstance(name, str) or not name:
            raise SolasError(f"{what}: {kind!s}={name} must be KIND=FILE with KIND one of {', '.join(KINDS)}")
        if kind in out:
            raise SolasError(f"{what}: {kind} is given twice")
        files = KINDS[kind].extra["files"]
        if not name.lower().endswith(files) or (pattern and ("{stem}" not in name or "/" in name)):
            shape = "a file name with {stem} beside each frame, " if pattern else ""
            raise SolasError(f"{what}: {kind} file {name!r} must be {shape}ending in {' or '.join(files)}")
        out[kind] = name
    return tuple(out.items())


def flare_layers(direct, stray) -> dict[str, Any]:
    """The `FLARE_LAYERS` of a direct and a stray-light image (H×W×C): the stray light's channel mean and its ratio
    to the direct image's (0 where no stray light arrives, `MAX_RATIO` where the direct image is dark), float32."""
    import numpy as np

    flare = np.asarray(stray, dtype=np.float64).mean(axis=-1)
    base = np.asarray(direct, dtype=np.float64).mean(axis=-1)
    lit = flare > 0
    ratio = np.where(lit & (base > 0), flare / np.where(base > 0, base, 1.0), np.where(lit, MAX_RATIO, 0.0))
    return {FLARE_LAYERS[0]: flare.astype(np.float32), FLARE_LAYERS[1]: np.minimum(ratio, MAX_RATIO).astype(np.float32)}
