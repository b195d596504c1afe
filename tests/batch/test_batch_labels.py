"""`batch degrade --label-pattern`: each frame's label files beside it, warped with the frame (as `degrade
--labels` does one), recorded in the manifest, never taken as frames; a depth-aware batch carries them too."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from strict_json import strict_loads

from solas_mi import SolasError
from solas_mi.cli import main
from solas_mi.convolution.spec import DegradeSpec

PATTERNS = "instance={stem}_ids.png,boxes={stem}_boxes.json"


def discs(shape=(48, 64)):
    rows, cols = np.indices(shape)
    ids = np.zeros(shape)
    for k, (cy, cx) in enumerate(((12, 14), (12, 46), (34, 30)), start=1):
        ids[(rows - cy) ** 2 + (cols - cx) ** 2 <= 36] = k
    return ids


def with_labels(folder: Path, stem: str, ids: np.ndarray) -> None:
    """`stem`'s ids (an 8-bit PNG, a name no label word ends) and a box around its first disc."""
    from solas_mi.imageio import write_png

    write_png(folder / f"{stem}_ids.png", ids / 255.0, encoded=True)
    (folder / f"{stem}_boxes.json").write_text(json.dumps({"annotations": [{"id": 1, "bbox": [8, 6, 13, 13]}]}))


@pytest.fixture(scope="module")
def depth_grid_file(tmp_path_factory, doublet):
    from solas_mi.psf.depth import depth_grid
    from solas_mi.psf.spec import GridSpec

    g = depth_grid(
        doublet,
        GridSpec(
            grid=(3, 4),
            wavelengths_nm=[531.0],
            size=32,
            pitch_um=4.0,
            method="geometric",
            rays=32,
            distances_m=(math.inf, 10.0),
        ),
    )
    path = tmp_path_factory.mktemp("grid") / "g.exr"
    g.write(str(path))
    return path, g


def test_a_depth_aware_batch_carries_its_labels(tmp_path, depth_grid_file):
    """The acceptance: `--depth-pattern` with a grid over distance and label patterns; each item's labels are
    warped by its own depth's mapping (as `degrade_file` warps them for one frame), written beside it, named
    in the manifest; the label files and depth maps are no frames; a re-run skips the finished item."""
    from solas_mi.batch.degrade import degrade_batch
    from solas_mi.convolution.output import degrade_file
    from solas_mi.imageio import image_channels, read_exr, write_exr
    from solas_mi.psf.depth import read_grid

    grid_path, _ = depth_grid_file
    folder = tmp_path / "frames"
    folder.mkdir()
    ids = discs()
    write_exr(folder / "a.exr", image_channels((ids > 0).astype(float)), {})
    write_exr(folder / "a_depth.exr", {"Z": np.where(ids > 0, 10.0, np.inf).astype(np.float32)}, infinite=True)
    with_labels(folder, "a", ids)
    spec = DegradeSpec(depth_pattern="{stem}_depth.exr", label_patterns=PATTERNS)
    out = tmp_path / "out"
    result = degrade_batch([folder], out, spec, psf_grid=grid_path, workers=1, progress=False)
    assert [(Path(j.input).name, j.status) for j in result.jobs] == [("a.exr", "done")]
    (job,) = result.jobs
    assert job.label_outputs == [str(out / "a.labels.exr"), str(out / "a.boxes.json")]
    m = strict_loads((out / "batch.json").read_text())
    assert m["labels"]["instance"] == {
        "pattern": "{stem}_ids.png",
        "rule": "pick",
        "how": m["labels"]["instance"]["how"],
    }
    assert m["items"][0]["params"]["labels"] == {
        "instance": str(folder / "a_ids.png"),
        "boxes": str(folder / "a_boxes.json"),
    }
    assert set(m["items"][0]["outputs"]) == {str(out / n) for n in ("a.exr", "a.png", "a.labels.exr", "a.boxes.json")}
    one = tmp_path / "one"
    one.mkdir()
    degrade_file(
        folder / "a.exr",
        read_grid(str(grid_path)),
        grid_path,
        one / "a.exr",
        one / "a.png",
        spec,
        depth=folder / "a_depth.exr",
        labels={"instance": folder / "a_ids.png", "boxes": folder / "a_boxes.json"},
    )
    batch_layers, batch_meta = read_exr(out / "a.labels.exr")
    assert all(np.array_equal(v, read_exr(one / "a.labels.exr")[0][k]) for k, v in batch_layers.items())
    assert "1/distance" in batch_meta["labels"]["mapping"] and set(np.unique(batch_layers["instance.id"])) <= {
        0,
        1,
        2,
        3,
    }
    assert (
        json.loads((out / "a.boxes.json").read_text())["annotations"]
        == json.loads((one / "a.boxes.json").read_text())["annotations"]
    )
    again = degrade_batch([folder], out, spec, psf_grid=grid_path, workers=1, progress=False)
    assert [j.status for j in again.jobs] == ["skipped"]
    (out / "a.labels.exr").unlink()
    assert [
        j.status for j in degrade_batch([folder], out, spec, psf_grid=grid_path, workers=1, progress=False).jobs
    ] == ["done"]
    assert (out / "a.labels.exr").is_file()


def test_label_files_are_no_frames_and_a_missing_one_is_named(batch_inputs, capsys):
    """The frames' label files by the patterns are theirs, whatever their names (ids in a PNG, a depth map
    named as no label word says): not frames, not named as skipped; one missing is named."""
    from solas_mi.batch.degrade import plan_batch
    from solas_mi.imageio import write_exr

    frames = batch_inputs.write(2)
    for frame in frames:
        with_labels(frame.parent, frame.stem, discs())
        write_exr(frame.with_name(f"{frame.stem}_m.exr"), {"Z": np.full((48, 64), 9.0)})
    spec = DegradeSpec(label_patterns=PATTERNS + ",depth={stem}_m.exr")
    p = plan_batch([batch_inputs.images], batch_inputs.root / "out", spec, psf_grid=batch_inputs.grid)
    assert [Path(j.input).name for j in p.jobs] == [f.name for f in frames]
    assert sorted(p.jobs[0].params["labels"]) == sorted(kind for kind, _ in spec.label_patterns)
    assert "skipped" not in capsys.readouterr().err
    (frames[1].parent / f"{frames[1].stem}_ids.png").unlink()
    with pytest.raises(
        SolasError,
        match=r"1 image\(s\) have no instance labels by the pattern '\{stem\}_ids.png', "
        r"e\.g\. .*frame001_ids\.png",
    ):
        plan_batch(
            [batch_inputs.images],
            batch_inputs.root / "out",
            DegradeSpec(label_patterns=PATTERNS),
            psf_grid=batch_inputs.grid,
        )


def test_an_item_with_a_bad_label_fails_alone_and_writes_nothing(batch_inputs, capsys):
    frames = batch_inputs.write(2)
    with_labels(frames[0].parent, frames[0].stem, discs())
    with_labels(frames[1].parent, frames[1].stem, discs((48, 60)))  # another size than its frame
    out = batch_inputs.root / "out"
    argv = [
        "batch",
        "degrade",
        str(batch_inputs.images),
        "--psf-grid",
        str(batch_inputs.grid),
        "-o",
        str(out),
        "--label-pattern",
        PATTERNS,
        "--workers",
        "1",
        "--quiet",
    ]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "frame001_ids.png' are 60x48 pixels; the frame" in err and "is 64x48" in err, err
    assert sorted(p.name for p in out.iterdir() if p.name.startswith("frame")) == [
        "frame000.boxes.json",
        "frame000.exr",
        "frame000.labels.exr",
        "frame000.png",
    ]
    assert main(argv[:-3] + ["--dry-run"]) == 0
    assert "EXR + PNG + warped labels EXR + warped labels JSON per image" in capsys.readouterr().out


def test_a_frame_may_hold_its_own_labels(batch_inputs):
    """A frame whose EXR carries its label layers beside its image (as `render --labels` writes them) is its
    own label file: `--label-pattern instance={stem}.exr` reads them there and the frame stays an input."""
    from solas_mi.batch.degrade import degrade_batch
    from solas_mi.imageio import read_exr, write_exr

    ids = discs()
    frame = batch_inputs.images / "own.exr"
    write_exr(frame, {"R": ids / 3, "G": ids / 3, "B": ids / 3, "instance.id": ids})
    out = batch_inputs.root / "out"
    result = degrade_batch(
        [frame],
        out,
        DegradeSpec(label_patterns="instance={stem}.exr"),
        psf_grid=batch_inputs.grid,
        workers=1,
        progress=False,
    )
    assert [j.status for j in result.jobs] == ["done"]
    assert set(np.unique(read_exr(out / "own.labels.exr")[0]["instance.id"])) <= {0, 1, 2, 3}
