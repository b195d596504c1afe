"""A frame's labels warped by exactly the mapping its image went through (`mapping.Mapping`): the label
files of `labelkinds.KINDS` read and checked (`read_labels`), each kind moved by its rule
(`labelkinds.RULES`, `warp_labels`), written beside the degraded frame (`label_outputs`).

Each output pixel q takes its label from its source p, the input point the mapping lands on q (the
reference wavelength's chief ray; the image's other wavelengths move by their lateral colour as well).
Ids, masks and normals are picked, never blended: the value of one of the four pixels around the
source point, each with the probability of its bilinear weight, by a fixed ordered dither (`dither`).
Rounding the source point instead moves a region by whole pixels: a shift of 0.3 px moved a disc's ids
by 0 (picked: 0.3 within 0.1 px), and through the wide angle the warped discs' centroids lay up to 0.28 px
(mean 0.17) from their light's in the degraded frame (picked: 0.13, mean 0.05;
tests/convolution/test_degrade_labels.py). Depth is interpolated within a surface. A value is a property
of the scene point the pixel sees, and the degraded frame sees each point along the same direction from
the same centre as the input frame: the lens moves where a direction lands on the sensor, not the
direction. So depth stays metres along the same optical axis (or the same range), a normal in the
camera's or the world's frame stays the same vector; nothing is rotated, only the pixel that holds it
moves. Optical flow is a displacement between two frames taken by the same lens: both its ends move,
so its value is M(p + f) − M(p).

`labels.valid` is 1 where the source lies inside the input frame, 0 where it lies beyond its border:
there the image shows what the convolution's boundary rule put beyond it (`edge`: the border repeated,
`reflect`: mirrored, `zero`: black), and so do the labels (`zero`: 0), with `labels.valid` 0. The
depth's inf (sky) is written 0: no layer holds an infinity (`render --labels`' convention: 0, nothing
met). Boxes and keypoints (COCO's JSON layout): points moved forward by M; a box becomes the bounding
box of its moved outline, clipped to the frame (one wholly outside is dropped and counted); a keypoint
landing outside the frame is marked not labelled (0, 0, 0); an `area` is scaled by the mapping's local
area change at the box's centre.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np

from ..errors import SolasError
from ..labelkinds import KINDS, RULES, VALID
from .depth import SILHOUETTE_RATIO
from .mapping import CHUNK_PIXELS, Mapping

LAYERS_SUFFIX, BOXES_SUFFIX = ".labels.exr", ".boxes.json"
BAYER = 8  # the ordered dither's period (pixels)
# memory of warping (bytes), fitted to the peak allocation (tracemalloc) from 320x216 to 2560x1728 through the
# wide angle: per pixel, the source points, validity and picks, and each channel's values read and written; then
# the larger of the inversion's temporaries (per pixel of its chunk, `mapping.CHUNK_PIXELS`) and the costliest
# rule's (`labelkinds.RULES`, per pixel of the frame: they are freed in turn)
MAPPING_BYTES, CHANNEL_BYTES, SOLVE_BYTES = 40, 16, 200
RULE_BYTES = {"pick": 16, "surface": 102, "flow": 160, "points": 0}
SNAP_PX = 1e-6  # a source point this near a pixel centre is on it (the mapping's identity, to rounding)


def label_outputs(output: str | Path, kinds, flare: bool = False) -> dict[str, Path]:
    """The files the labels `kinds` of the degraded frame `output` are written to, beside it: "layers", its
    image kinds' layers in OUT.labels.exr (with `labels.valid`) and, with `flare` (degrade --ghosts), the flare
    label's; "boxes", a JSON kind's annotations in OUT.boxes.json."""
    output, kinds = Path(output), list(kinds)
    layered = {bool(KINDS[k].extra["layers"]) for k in kinds} | ({True} if flare else set())
    return {
        **({"layers": output.with_suffix(LAYERS_SUFFIX)} if True in layered else {}),
        **({"boxes": output.with_suffix(BOXES_SUFFIX)} if False in layered else {}),
    }


def memory_bytes(pixels: int, kinds) -> int:
    """Memory (bytes) that warping the labels `kinds` of a frame of `pixels` adds: 0 for none (measured at
    1280x864: 77 B a pixel for instance ids, 309 for ids, depth, normals and flow together; estimated 103 and
    312)."""
    kinds = list(kinds)
    if not kinds:
        return 0
    channels = sum(len(KINDS[k].extra["layers"]) for k in kinds)
    work = max(min(pixels, CHUNK_PIXELS) * SOLVE_BYTES, pixels * max(RULE_BYTES[KINDS[k].extra["rule"]] for k in kinds))
    return pixels * (MAPPING_BYTES + CHANNEL_BYTES * channels) + work


def read_labels(files, shape: tuple[int, int], frame: str | Path) -> dict:
    """Each kind's values, read from `files` ((kind, file) pairs or a dict), image kinds checked to be the
    frame's `shape` (rows, columns): a SolasError naming the file, its size and the frame's otherwise."""
    out = {}
    for kind, path in files.items() if isinstance(files, dict) else files:
        values = KINDS[kind].function(path)
        if KINDS[kind].extra["layers"] and values.shape[:2] != tuple(shape):
            raise SolasError(
                f"{kind} labels {str(path)!r} are {values.shape[1]}x{values.shape[0]} pixels; the frame "
                f"{str(frame)!r} is {shape[1]}x{shape[0]}: label images must be the frame's size"
            )
        out[kind] = (values, str(path))
    return out


def _index(i: np.ndarray, n: int, boundary: str) -> tuple[np.ndarray, np.ndarray | None]:
    """Pixel indices `i` (integers as floats) made valid by the boundary rule, and where they are kept
    (None: everywhere; `zero`: only inside)."""
    if boundary == "reflect":  # about the border's outer edge: −1 → 0, n → n − 1
        i = np.where(i < 0, -1 - i, i)
        i = np.where(i > n - 1, 2 * n - 1 - i, i)
    kept = ((i >= 0) & (i <= n - 1)) if boundary == "zero" else None
    return np.clip(i, 0, n - 1).astype(np.int64), kept


def dither(height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """A fixed dither in (0, 1) per pixel and axis (H, W): Bayer's 8×8 ordered dither (B. E. Bayer, 1973),
    transposed for the rows, so that along an edge the share of pixels rounded up is the fraction the shift
    asks for (of the R2 sequence, interleaved gradient noise and random numbers tried, it put the warped
    discs' centroids nearest the mapped ones)."""
    bayer = np.zeros((1, 1))
    while len(bayer) < BAYER:
        bayer = np.block([[4 * bayer, 4 * bayer + 2], [4 * bayer + 3, 4 * bayer + 1]])
    r, c = np.ogrid[:height, :width]
    return (bayer[r % BAYER, c % BAYER] + 0.5) / BAYER**2, (bayer[c % BAYER, r % BAYER] + 0.5) / BAYER**2


class Sampler:
    """The labels' view of the mapping: each output pixel's source point, its validity, and each image
    rule of `labelkinds.RULES` as the method of its name (`pick`, `surface`, `flow`)."""

    def __init__(self, mapping: Mapping, boundary: str):
        self.mapping, self.boundary = mapping, boundary
        self.cols, self.rows, self.found = mapping.sources()
        w, h = mapping.width, mapping.height
        self.valid = (self.cols >= -0.5) & (self.cols < w - 0.5) & (self.rows >= -0.5) & (self.rows < h - 0.5)
        ux, uy = dither(h, w)
        # the source point rounded up with the probability of its fraction (a point on a pixel stays there)
        self.picked = [
            np.floor(np.where(np.abs(v - np.rint(v)) < SNAP_PX, np.rint(v), v) + u)
            for v, u in ((self.cols, ux), (self.rows, uy))
        ]

    def take(self, values: np.ndarray, cols: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """values (H, W, C) at the whole pixels (cols, rows), by the boundary rule beyond the frame (a valid
        pixel, whose source lies inside it, takes the border's value rather than `zero`'s 0)."""
        c, kc = _index(cols, self.mapping.width, self.boundary)
        r, kr = _index(rows, self.mapping.height, self.boundary)
        out = values[r, c]
        return out if kc is None else out * (kc & kr | self.valid)[..., None]

    def pick(self, values: np.ndarray) -> np.ndarray:
        return self.take(values, *self.picked)

    def surface(self, values: np.ndarray) -> np.ndarray:
        """Bilinear between the four source pixels where they hold finite positive depths within
        SILHOUETTE_RATIO of each other (one surface), else picked; inf written 0."""
        c0, r0 = np.floor(self.cols), np.floor(self.rows)
        s, t = (self.cols - c0)[..., None], (self.rows - r0)[..., None]
        v = [self.take(values, c0 + dc, r0 + dr) for dr in (0, 1) for dc in (0, 1)]
        lo, hi = np.minimum.reduce(v), np.maximum.reduce(v)
        with np.errstate(invalid="ignore", over="ignore"):
            one = np.isfinite(hi) & (lo > 0) & (hi <= SILHOUETTE_RATIO * lo)
            mixed = (1 - t) * ((1 - s) * v[0] + s * v[1]) + t * ((1 - s) * v[2] + s * v[3])
        out = np.where(one, mixed, self.pick(values))
        return np.where(np.isfinite(out), out, 0.0)

    def flow(self, values: np.ndarray) -> np.ndarray:
        """The picked source pixel's flow f, both its ends moved: M(p + f) − M(p), p the source point."""
        f = self.pick(values)
        at = (self.cols, self.rows)  # the point's own depth picks its distance nodes at both ends
        x1, y1 = self.mapping.forward(self.cols + f[..., 0], self.rows + f[..., 1], at)
        x0, y0 = self.mapping.forward(self.cols, self.rows, at)
        return np.stack([x1 - x0, y1 - y0], axis=-1)


def warp_labels(labels: dict, mapping: Mapping, boundary: str) -> tuple[dict, dict | None, dict]:
    """The labels of `read_labels` warped by `mapping` (the image's boundary rule beyond the frame): the
    image kinds' layers (name → H×W float32, `labels.valid` with them), the moved annotations (None
    without), and the metadata of what was done."""
    sampler = Sampler(mapping, boundary)
    layers, annotations, kinds = {}, None, {}
    for kind, (values, path) in labels.items():
        entry = KINDS[kind]
        rule = entry.extra["rule"]
        about = {"file": path, "rule": rule, "how": RULES[rule]}
        if rule == "points":
            annotations, moved = move_annotations(values, mapping)
            about.update(moved)
        else:
            warped = getattr(sampler, rule)(values)
            if boundary == "zero":  # beyond the border the image is black: nothing there
                warped = warped * sampler.valid[..., None]
            layers.update({name: warped[..., k].astype(np.float32) for k, name in enumerate(entry.extra["layers"])})
            about["layers"] = list(entry.extra["layers"])
        kinds[kind] = about
    if layers:
        layers[VALID] = sampler.valid.astype(np.float32)
    meta = {
        "kinds": kinds,
        **mapping.meta(),
        "boundary": boundary,
        **sampler.found,
        "valid_fraction": float(sampler.valid.mean()),
        "valid": f"{VALID}: 1 where the pixel's source lies inside the input frame, 0 where beyond its border "
        f"(labels there follow the boundary rule {boundary!r}, as the image does)",
        "coordinates": "pixel centres at whole (column, row); the JSON's points as COCO's (0, 0: the top-left "
        "corner of the first pixel)",
    }
    return layers, annotations, meta


def _move(mapping: Mapping, xs, ys) -> tuple[np.ndarray, np.ndarray]:
    """COCO points (x, y) (pixel edges) moved by the mapping."""
    c, r = mapping.forward(np.asarray(xs, dtype=np.float64) - 0.5, np.asarray(ys, dtype=np.float64) - 0.5)
    return c + 0.5, r + 0.5


def _box(a: dict, mapping: Mapping) -> list[float] | None:
    """The bounding box [x, y, w, h] of box `a["bbox"]`'s outline (a point per pixel along each side) moved,
    clipped to the frame; None where none of it is left; `a["area"]` scaled as the box's centre's area."""
    x, y, w, h = a["bbox"]
    n = int(math.ceil(max(w, h))) + 2
    u = np.linspace(0.0, 1.0, n)
    ox = np.concatenate([x + w * u, x + w * u, np.full(n, x), np.full(n, x + w)])
    oy = np.concatenate([np.full(n, y), np.full(n, y + h), y + h * u, y + h * u])
    mx, my = _move(mapping, ox, oy)
    x0, x1 = np.clip([mx.min(), mx.max()], 0, mapping.width)
    y0, y1 = np.clip([my.min(), my.max()], 0, mapping.height)
    if not (x1 > x0 and y1 > y0):
        return None
    if isinstance(a.get("area"), (int, float)) and not isinstance(a.get("area"), bool):
        cx, cy = _move(
            mapping,
            [x + w / 2 - 0.5, x + w / 2 + 0.5, x + w / 2, x + w / 2],
            [y + h / 2, y + h / 2, y + h / 2 - 0.5, y + h / 2 + 0.5],
        )
        a["area"] = float(a["area"]) * abs((cx[1] - cx[0]) * (cy[3] - cy[2]) - (cx[3] - cx[2]) * (cy[1] - cy[0]))
    return [float(x0), float(y0), float(x1 - x0), float(y1 - y0)]


def move_annotations(data: dict, mapping: Mapping) -> tuple[dict, dict]:
    """COCO-layout annotations (`labelkinds.read_annotations`) moved by the mapping (module docstring), and
    counts of what was dropped or marked."""
    out = copy.deepcopy(data)
    kept, dropped, hidden = [], 0, 0
    for a in out["annotations"]:
        if "bbox" in a:
            a["bbox"] = _box(a, mapping)
            if a["bbox"] is None:
                dropped += 1
                continue
        if a.get("keypoints"):
            k = np.asarray(a["keypoints"], dtype=np.float64).reshape(-1, 3)
            x, y = _move(mapping, k[:, 0], k[:, 1])
            labelled = k[:, 2] > 0
            inside = (x >= 0) & (x <= mapping.width) & (y >= 0) & (y <= mapping.height)
            hidden += int((labelled & ~inside).sum())
            k[:, 0], k[:, 1] = np.where(labelled & inside, x, 0.0), np.where(labelled & inside, y, 0.0)
            k[:, 2] = np.where(inside, k[:, 2], 0.0)
            a["keypoints"] = [v if i % 3 != 2 else int(v) for i, v in enumerate(k.ravel().tolist())]
        if a.get("segmentation"):
            a["segmentation"] = [
                np.stack(_move(mapping, s[0::2], s[1::2]), axis=-1).ravel().tolist() for s in a["segmentation"]
            ]
        kept.append(a)
    out["annotations"] = kept
    return out, {"annotations": len(kept), "boxes_dropped_outside": dropped, "keypoints_moved_outside": hidden}


def label_writers(targets: dict[str, Path], layers: dict, annotations: dict | None, meta: dict) -> dict:
    """Each file of `targets` (`label_outputs`) → its writer of a temporary path: the warped layers as a
    float32 EXR (`meta` in its header as "labels"), the moved annotations as JSON (`meta` under
    "solas_mi_labels")."""
    from .. import jsonio
    from ..imageio import write_exr, write_text

    writers = {
        "layers": lambda tmp: write_exr(tmp, layers, {"labels": meta}),
        "boxes": lambda tmp: write_text(
            tmp, jsonio.dumps({**(annotations or {}), "solas_mi_labels": meta}, indent=1) + "\n"
        ),
    }
    return {path: writers[what] for what, path in targets.items()}
