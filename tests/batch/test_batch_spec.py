"""A degrade batch's options as one `DegradeSpec`: the batch's identity is the one finished batches
hold (they resume), and the manifest and each output's header state the options the user gave, the
same through Python and the command line."""

import hashlib
import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest
from strict_json import strict_loads

from solas_mi import SolasError
from solas_mi.batch import degrade_batch
from solas_mi.batch.cache import GridCache, file_hash
from solas_mi.batch.degrade import plan_batch
from solas_mi.cli import main
from solas_mi.convolution.spec import DegradeSpec
from solas_mi.imageio import read_exr, write_exr
from solas_mi.isp.camera import load_camera
from solas_mi.optics.frame import FrameCamera
from solas_mi.psf.spec import GridSpec

FX = float(32 / np.tan(np.radians(1.5)))  # the 64-px frames span ±1.5°
FRAME = FrameCamera("pinhole", intrinsics=(FX, FX, 31.5, 23.5))


def manifest(folder: Path) -> dict:
    return strict_loads((folder / "batch.json").read_text())


def former_identity(
    grid_id: str,
    method="interp",
    boundary="edge",
    linear=False,
    output_format="exr",
    depth_pattern=None,
    occlusion="filled",
    silhouette="nearest",
    frame=None,
    camera=None,
) -> str:
    """The batch id as batches before DegradeSpec computed it from their loose options (the ids in the
    manifests they left): a batch resumes only when its id is unchanged."""
    identity = (
        [grid_id, method, boundary, linear]
        + ([output_format] if output_format != "exr" else [])
        + ([depth_pattern, occlusion, silhouette] if depth_pattern is not None else [])
        + ([asdict(frame)] if frame is not None else [])
        + ([camera.describe()] if camera is not None else [])
    )
    return hashlib.sha256(json.dumps(identity).encode()).hexdigest()[:16]


def test_the_batch_identity_is_the_one_finished_batches_hold(batch_inputs, doublet):
    (frame,) = batch_inputs.write(1)
    write_exr(frame.with_name("frame000_depth.exr"), {"Z": np.full((48, 64), 10.0, np.float32)})
    (batch_inputs.root / "sensor.toml").write_text('[sensor]\ncfa = "RCCB"\npixel_pitch_um = 2.0\n')
    camera = load_camera(str(batch_inputs.root / "sensor.toml"), 0.25, "default", 3)
    options = [
        {},
        {"method": "patch", "boundary": "zero", "linear": True},
        {"output_format": "exr-half"},
        {"output_format": "png16", "boundary": "reflect"},
        {"depth_pattern": "{stem}_depth.exr"},
        {"depth_pattern": "{stem}_depth.exr", "occlusion": "none", "silhouette": "as-given"},
        {"frame": FRAME},
        {"camera": camera},
        {"frame": FRAME, "camera": camera, "output_format": "exr-half"},
    ]
    grid_id = file_hash(batch_inputs.grid)
    keys = set()
    for given in options:
        p = plan_batch(
            [batch_inputs.images], batch_inputs.root / "out", DegradeSpec(**given), psf_grid=batch_inputs.grid
        )
        assert p.key == former_identity(grid_id, **given), given
        keys.add(p.key)
    assert len(keys) == len(options)  # each option is part of the identity
    cache = GridCache(batch_inputs.root / "cache")
    grid = GridSpec(grid=(2, 2), size=16, pupil_samples=16)
    p = plan_batch(
        [batch_inputs.images],
        batch_inputs.root / "out",
        DegradeSpec(grid_spec=grid, linear=True),
        lens=doublet,
        cache=cache,
    )
    assert p.key == former_identity(cache.path(doublet, grid).stem, linear=True)


def test_the_manifest_and_headers_state_the_options_given(batch_inputs, capsys):
    """Python (a DegradeSpec) and the command line (its flags) with the same options write the same
    manifest header and output headers, stating what was given; either resumes the other's batch."""
    batch_inputs.write(2)
    given = {"method": "patch", "boundary": "reflect", "linear": True, "output_format": "exr-half", "frame": FRAME}
    spec = DegradeSpec(**given)
    py, cli = batch_inputs.root / "py", batch_inputs.root / "cli"
    result = degrade_batch([batch_inputs.images], py, spec, psf_grid=batch_inputs.grid, workers=1, progress=False)
    assert result.count("done") == 2
    argv = [
        "batch",
        "degrade",
        str(batch_inputs.images),
        "--psf-grid",
        str(batch_inputs.grid),
        "--workers",
        "1",
        "--quiet",
        "--method",
        "patch",
        "--boundary",
        "reflect",
        "--linear",
        "--format",
        "exr-half",
        "--intrinsics",
        ",".join(str(v) for v in FRAME.intrinsics),
    ]
    assert main([*argv, "-o", str(cli)]) == 0
    a, b = manifest(py), manifest(cli)
    assert {k: a[k] for k in ("method", "boundary", "linear", "format", "frame_camera")} == {
        "method": "patch",
        "boundary": "reflect",
        "linear": True,
        "format": "exr-half",
        "frame_camera": json.loads(json.dumps(asdict(FRAME))),
    }
    assert "camera" not in a and "lens_scale" not in a  # none given, none stated
    same = {k for k in a if k not in ("items", "updated", "summary")}
    assert {k: a[k] for k in same} == {k: b[k] for k in same} and a["batch_id"] == b["batch_id"]
    for name in ("frame000", "frame001"):
        channels, meta = read_exr(py / f"{name}.exr")
        _, other = read_exr(cli / f"{name}.exr")
        assert channels["R"].dtype == np.float16 and meta["output_format"] == "exr-half"
        assert (meta["method"], meta["boundary"], meta["input_encoding"]) == ("patch", "reflect", "linear")
        assert meta["frame_camera"] == FRAME.meta(64, 48)
        assert meta["batch"]["id"] == a["batch_id"]
        drop = ("seconds", "batch", "input")
        assert {k: v for k, v in meta.items() if k not in drop} == {k: v for k, v in other.items() if k not in drop}
    capsys.readouterr()
    assert main([*argv, "-o", str(py)]) == 0  # the command line finds the Python batch finished
    assert "0 done, 2 skipped" in capsys.readouterr().out


@pytest.mark.parametrize(
    "given, psf_grid, message",
    [
        ({"grid_spec": GridSpec()}, True, "grid_spec is for a grid computed from a lens"),
        ({"scale_lens": 5.0, "frame": FRAME}, True, "needs the lens the grid is computed from"),
        ({"scale_lens": 5.0}, False, "needs the frames' camera"),
    ],
)
def test_options_that_do_not_fit_the_grid_are_refused(batch_inputs, doublet, given, psf_grid, message):
    batch_inputs.write(1)
    source = {"psf_grid": batch_inputs.grid} if psf_grid else {"lens": doublet}
    with pytest.raises(SolasError, match=message):
        plan_batch([batch_inputs.images], batch_inputs.root / "out", DegradeSpec(**given), **source)
    assert not (batch_inputs.root / "out").exists()
