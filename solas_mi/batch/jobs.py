"""A batch's items and its manifest.

An item (`Job`) is one unit of work with its inputs and outputs; `kind` names what it does
("degrade", or "render" with its `seed` and the `params` of its sweep point). The manifest,
`batch.json` in the output folder, records each item's status ("pending", "done", "skipped",
"failed", "interrupted"), timings, seed, error, the input's checksum and the outputs' sizes, times and
checksums (SHA-256: what a re-run checks before it skips an item), beside what the whole batch
shares (the grid's hash, the lens's hash, the method). It is rewritten atomically, so it is valid
JSON whenever it is read, also after the batch was killed.
"""

from __future__ import annotations

import glob
import os
import re
import sys
import time
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from .. import jsonio
from ..errors import SolasError
from ..labelkinds import KINDS, VALID
from ..outputs import inside, safe_name
from ..render.labels import LABELS
from ..render.mitsuba import SCENE_SUFFIXES  # Mitsuba scene files (render items)
from ..userfiles import check, read_text
from .cache import file_hash

MANIFEST = "batch.json"
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr")
SAVE_EVERY_S = 1.0  # the manifest is rewritten at most this often while items finish (and at the end)
# The label layers that renderers and simulators write beside their frames (ours as EXR layers,
# `render.labels`; CARLA, Kubric, AirSim as files): never frames. A file is one by the last word of its
# name after any frame number (a_depth.exr, street_0001_seg.png, depth_00042.exr) or, for an EXR, by
# its channels: every one a depth (Z, depth) or a label layer's (depth.Z, normal.X, labels.valid). The
# kinds of image labels (`labelkinds.KINDS`: not the JSON annotations) and those the render traces.
LABEL_WORDS = (
    *(k for k in KINDS if KINDS[k].extra["layers"]),
    *LABELS,
    VALID.split(".")[0],
    "seg",
    "segmentation",
    "instances",
    "normals",
)
DEPTH_CHANNELS = ("z", "depth")
_WORDS = re.compile(r"[^a-z0-9]+")
SHOWN_SKIPPED = 5  # skipped label layers named in the note (then a count)


@dataclass
class Job:
    """One item of a batch: it reads `input` and writes `output` (EXR) + `png`; `kind` "degrade" or
    "render" (`params`: lens, focus distance, sensor, pitch, spp, response of its sweep point)."""

    input: str
    output: str
    png: str
    kind: str = "degrade"
    seed: int | None = None  # degrading has no randomness; a render item records its seed here
    status: str = "pending"
    error: str | None = None
    seconds: float | None = None
    attempts: int = 0
    outputs: dict[str, list] = field(default_factory=dict)  # path → [size, mtime_ns, sha256/16] when finished
    input_hash: str | None = (
        None  # the input's SHA-256 (16 hex digits; a scene's with the files it reads) when finished
    )
    params: dict[str, Any] = field(default_factory=dict)
    label_outputs: list[str] = field(default_factory=list)  # the warped labels (`convolution.labels.label_outputs`)
    extras: list[str] = field(default_factory=list)  # more outputs: the camera's RAW and developed frame
    warnings: list[str] = field(default_factory=list)  # what the item's run warns of (a saturated RAW)

    def paths(self) -> tuple[str, ...]:
        """Every output of the item."""
        return (self.output, self.png, *self.label_outputs, *self.extras)

    def stamp(self) -> None:
        """Record the finished outputs' sizes, modification times and checksums and the input's
        checksum (how a re-run knows them)."""
        self.outputs = {p: [(s := os.stat(p)).st_size, s.st_mtime_ns, file_hash(p)] for p in self.paths()}
        self.input_hash = self.input_digest()

    def input_digest(self) -> str:
        """The input's SHA-256 (16 hex digits); a scene file's covers every file it reads (includes,
        meshes, textures, ...: `render.user_scene.scene_files`), named and hashed, so that a texture
        replaced under the same name is an input changed."""
        if self.kind != "render" or Path(self.input).suffix.lower() not in SCENE_SUFFIXES:
            return file_hash(self.input)
        import hashlib

        from ..render.user_scene import scene_files

        digest = hashlib.sha256()
        for path in scene_files(self.input):
            try:
                digest.update(f"{path}\0{file_hash(path)}\n".encode())
            except OSError:  # unreadable to us (its render failed or did without): its name stands for it
                digest.update(f"{path}\0unreadable\n".encode())
        return digest.hexdigest()[:16]

    def finished(self) -> bool:
        """Every output is there as this batch wrote it (same sizes, times and SHA-256 checksums; the
        record names exactly this item's outputs), made from this very input (its content's SHA-256: an
        input replaced by another file of the same name is done again)."""
        try:
            return (
                set(self.outputs) == set(self.paths())
                and all(
                    [(s := os.stat(p)).st_size, s.st_mtime_ns, file_hash(p)] == list(v) for p, v in self.outputs.items()
                )
                and self.input_hash == self.input_digest()
            )
        except (OSError, SolasError):  # an output or input gone, a scene that no longer reads
            return False


def label_layer(path: Path) -> str | None:
    """Why the image file `path` is a label layer written beside frames (`LABEL_WORDS`), not a frame;
    None for a frame."""
    words = [w for w in _WORDS.split(path.stem.lower()) if w]
    while words and words[-1].isdigit():  # a frame number
        words.pop()
    if words and words[-1] in LABEL_WORDS:
        return f"its name ends in {words[-1]!r}"
    if path.suffix.lower() != ".exr":
        return None
    from ..imageio import exr_channel_names

    names = exr_channel_names(path)
    layers = [n.lower().rsplit(".", 1) for n in names]
    if names and all(layer[0] in LABEL_WORDS if len(layer) == 2 else layer[0] in DEPTH_CHANNELS for layer in layers):
        return f"its channels ({', '.join(names)}) are labels, no image"
    return None


def say_skipped(skipped: list[tuple[Path, str]]) -> None:
    """Name on stderr the label layers (file, why) that a batch skipped."""
    if skipped:
        shown = "; ".join(f"{p.name} ({why})" for p, why in skipped[:SHOWN_SKIPPED])
        more = f"; and {len(skipped) - SHOWN_SKIPPED} more" if len(skipped) > SHOWN_SKIPPED else ""
        print(
            f"solas-mi batch: skipped {len(skipped)} label layer(s) (depth, segmentation, normal or flow maps), "
            f"not frames: {shown}{more}",
            file=sys.stderr,
            flush=True,
        )


def expand_inputs(
    inputs: Iterable[str | os.PathLike],
    suffixes: tuple[str, ...] = IMAGE_SUFFIXES,
    roots: dict[Path, Path] | None = None,
    skipped: list[tuple[Path, str]] | None = None,
) -> list[Path]:
    """Files from files, folders (their files ending in `suffixes`, sorted; with `roots`, the whole
    folder tree, each file's folder given recorded in `roots`) and glob patterns; each once, in the
    order given. Label layers (`label_layer`) are no inputs: they are skipped, and added to `skipped`
    as (file, why), or named on stderr (`say_skipped`) when no list is given. SolasError naming an
    input that matches nothing, or only label layers."""
    found: list[Path] = []
    labelled: list[tuple[Path, str]] = []
    for item in inputs:
        text = str(item)
        path = Path(text)
        if path.is_dir():
            files = path.rglob("*") if roots is not None else path.iterdir()
            matches = sorted(p for p in files if p.suffix.lower() in suffixes and p.is_file())
        elif path.exists():
            matches = [check(path, "batch input")]  # hashed before it is read: no FIFO nor device
        elif glob.has_magic(text):
            matches = sorted(Path(p) for p in glob.glob(text) if Path(p).is_file())
        else:
            raise SolasError(f"input {text!r} is not a file, a folder or a glob pattern that matches files")
        labels = [(p, why) for p in matches if p.suffix.lower() in IMAGE_SUFFIXES and (why := label_layer(p))]
        matches = [p for p in matches if p not in {label for label, _ in labels}]
        if not matches:
            only = (
                f"only label layers, no frames ({labels[0][0].name}: {labels[0][1]}); give the frames"
                if labels
                else f"no input files ({', '.join(suffixes)})"
            )
            raise SolasError(f"input {text!r} holds {only}")
        if roots is not None and path.is_dir():
            roots.update({p.resolve(): path.resolve() for p in matches})
        labelled.extend((Path(os.path.abspath(p)), why) for p, why in labels)
        found.extend(matches)
    if skipped is None:
        say_skipped(labelled)
    else:
        skipped.extend(labelled)
    given: dict[Path, Path] = {}  # each file once (by its target), under the name given (a link keeps its name)
    for p in found:
        given.setdefault(p.resolve(), Path(os.path.abspath(p)))
    unique = list(given.values())
    if not unique:
        raise SolasError("no input images given")
    return unique


def plan(
    inputs: list[Path],
    out_dir: Path,
    roots: dict[Path, Path] | None = None,
    suffixes: tuple[str, str] = (".exr", ".png"),
) -> list[Job]:
    """One degrade job per input: OUT_DIR/<name>.exr + .png (or the two `suffixes`: data, then preview
    or metadata), or, for a file found in a folder tree (`roots`: file → the folder given), OUT_DIR/<its
    path in the tree>.exr. SolasError when two inputs would write the same output or an output would
    replace an input."""
    jobs = []
    seen: dict[Path, Path] = {}  # output → the input that writes it
    sources = set(inputs)
    for path in inputs:
        below = path.relative_to(roots[path]).parent if roots and path in roots else Path()
        output = inside(
            out_dir.joinpath(*(safe_name(part) for part in below.parts)), f"{safe_name(path.stem)}{suffixes[0]}"
        )
        if output in seen:
            raise SolasError(
                f"inputs {str(seen[output])!r} and {str(path)!r} would both write {output}; "
                "give them different names or run them as separate batches"
            )
        seen[output] = path
        for target in (output, output.with_suffix(suffixes[1])):
            if target in sources:
                raise SolasError(f"output {target} would replace the input of the same name; choose another -o")
        jobs.append(Job(str(path), str(output), str(output.with_suffix(suffixes[1]))))
    return jobs


def add_outputs(
    jobs: list[Job], more: Callable[[str], list[str]], sources: Iterable[str | os.PathLike], into: str = "extras"
) -> None:
    """Give each job the outputs `more(job.output)` besides those it has, as its field `into` (`extras`, or
    `label_outputs`); SolasError when one would be another item's output or an input."""
    taken = {p: job.input for job in jobs for p in job.paths()}
    inputs = {str(Path(s)) for s in sources}
    for job in jobs:
        setattr(job, into, more(job.output))
        for path in getattr(job, into):
            if path in taken or path in inputs:
                raise SolasError(
                    f"output {path} of {job.input!r} would replace "
                    f"{'an input' if path in inputs else 'an output of ' + repr(taken[path])}; "
                    "rename the input or run it as a separate batch"
                )
            taken[path] = job.input


class Manifest:
    """A batch's record, ``batch.json``: what the batch shares and each item's state, saved atomically.

    Parameters
    ----------
    path : Path
        The file.
    header : dict
        What the batch shares (its id, options, grid, runner).
    jobs : list of Job
        Its items.
    """

    def __init__(self, path: Path, header: dict[str, Any], jobs: list[Job]):
        self.path, self.header, self.jobs = path, header, jobs
        self._saved = 0.0

    @staticmethod
    def previous(path: Path) -> dict[str, Any]:
        """The manifest a former run left.

        Parameters
        ----------
        path : Path
            The file.

        Returns
        -------
        dict
            Its content; empty when there is none or it cannot be read.
        """
        try:
            data = jsonio.loads(read_text(path, "record"))
            return data if isinstance(data, dict) else {}
        except (OSError, ValueError):
            return {}

    def resume(self, key: str) -> int:
        """Mark "skipped" each job that a former run of the same batch finished, its outputs unchanged.

        Parameters
        ----------
        key : str
            The batch's id: a former run of another batch finished nothing of this one.

        Returns
        -------
        int
            The jobs skipped (same input, output and sweep point).
        """
        old = self.previous(self.path)
        if old.get("batch_id") != key:
            return 0
        done = {
            (i.get("input"), i.get("output")): i for i in old.get("items", []) if i.get("status") in ("done", "skipped")
        }
        skipped = 0
        for job in self.jobs:
            before = done.get((job.input, job.output))
            if before is not None and before.get("params", {}) == jsonio.loads(jsonio.dumps(job.params)):
                job.outputs, job.input_hash = before.get("outputs") or {}, before.get("input_hash")
                if isinstance(job.outputs, dict) and job.finished():
                    job.status, job.seconds, job.seed = "skipped", before.get("seconds"), before.get("seed")
                    job.warnings = list(before.get("warnings") or [])
                    skipped += 1
                else:
                    job.outputs, job.input_hash = {}, None
        return skipped

    def summary(self) -> dict[str, int]:
        """How many jobs are in each state.

        Returns
        -------
        dict
            State ("done", "failed", "skipped", ...) → count.
        """
        counts: dict[str, int] = {}
        for job in self.jobs:
            counts[job.status] = counts.get(job.status, 0) + 1
        return counts

    def save(self, force: bool = True) -> None:
        """Rewrite the manifest atomically.

        Parameters
        ----------
        force : bool, default True
            False: not when it was saved under `SAVE_EVERY_S` ago.
        """
        from ..imageio import write_text

        now = time.monotonic()
        if not force and now - self._saved < SAVE_EVERY_S:
            return
        data = {
            **self.header,
            "updated": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "summary": self.summary(),
            "items": [asdict(job) for job in self.jobs],
        }
        write_text(self.path, jsonio.dumps(data, indent=1) + "\n")
        self._saved = now
