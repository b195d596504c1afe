"""The render stage's commands (`render.commands`): `scene`, `render`, `render-image`, and the render
settings they build (`render.spec.RenderSpec`)."""

import math

import numpy as np
import pytest
from PIL import Image

from solas_mi.cli import main
from solas_mi.errors import SolasError
from solas_mi.imageio import read_exr
from solas_mi.render.spec import MAX_RINGS, RenderSpec


def test_scene_and_render_commands(tmp_path):
    """`solas-mi scene` writes an editable scene; `solas-mi render` renders it with overrides."""
    scene_dir = tmp_path / "scene"
    assert main(["scene", "solas-doublet", "-o", str(scene_dir), "--sensor", "16x12", "--rings", "16"]) == 0
    xml = scene_dir / "scene.xml"
    assert (scene_dir / "meshes" / "surface1.ply").is_file() and (scene_dir / "rocket.png").is_file()
    out = tmp_path / "r.exr"
    assert (
        main(
            [
                "render",
                str(xml),
                "-o",
                str(out),
                "--spp",
                "3",
                "--set",
                "response=lines",
                "--variant",
                "llvm_ad_spectral",
            ]
        )
        == 0
    )
    channels, meta = read_exr(out)
    assert sorted(channels) == ["B", "G", "R"] and channels["R"].shape == (12, 16)
    assert meta["spp"] == 3 and meta["response"].startswith("lines") and out.with_suffix(".png").is_file()
    assert main(["render", str(xml), "-o", str(tmp_path / "bad.exr"), "--set", "image=missing.png"]) == 2
    assert not (tmp_path / "bad.exr").exists()
    assert main(["render-image", "solas-doublet", str(tmp_path / "nope.png"), "-o", str(tmp_path / "x.exr")]) == 2


OUTPUT_FLAGS = {"help", "output", "png", "force"}  # where a render is written, not how it is rendered
RECORDED = {"calibration_model"}  # what its metadata records, not how it is rendered: a batch's own option
# where the lens is (`Lens.at`), not how it renders: a batch takes a lens file that states it (lens convert)
LENS_FLAGS = {"temperature_c", "pressure_kpa", "mount"}


@pytest.mark.parametrize(
    "argv, message",
    [
        (
            ["render-image", "solas-doublet", "{tmp}/photo.png", "--rings", "0", "-o", "{tmp}/x.exr"],
            f"cap rings 0 must be an integer from 2 to {MAX_RINGS}",
        ),
        (
            ["render-image", "solas-doublet", "{tmp}/photo.png", "--rings", "4096", "-o", "{tmp}/x.exr"],
            f"cap rings 4096 must be an integer from 2 to {MAX_RINGS}",
        ),
        (["scene", "solas-doublet", "-o", "{tmp}/scene", "--rings", "0"], "cap rings 0 must be an integer"),
        (
            ["render-image", "solas-doublet", "{tmp}/photo.png", "--response", "lines:531,531", "-o", "{tmp}/x.exr"],
            "camera response 'lines:531,531': each wavelength must differ",
        ),
        (
            ["render-image", "solas-doublet", "{tmp}/photo.png", "--response", "lines:531,x", "-o", "{tmp}/x.exr"],
            "lines needs comma-separated wavelengths in nm",
        ),
        (
            ["render-image", "solas-doublet", "{tmp}/photo.png", "--spp", "many", "-o", "{tmp}/x.exr"],
            "--spp 'many' must be an integer",
        ),
        (
            ["batch", "render", "{tmp}/photo.png", "--lens", "solas-doublet", "-o", "{tmp}/out", "--dask", "not a url"],
            "--dask 'not a url' must be a scheduler address, tcp://HOST:PORT",
        ),
    ],
)
def test_bad_settings_are_one_line_before_any_work(tmp_path, capsys, argv, message):
    Image.fromarray(np.full((24, 32), 128, np.uint8)).save(tmp_path / "photo.png")
    assert main([a.replace("{tmp}", str(tmp_path)) for a in argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["photo.png"]  # nothing written, nothing started


def _subparser(parser, *names):
    for name in names:
        (sub,) = [a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction"]
        parser = sub.choices[name]
    return parser


def _other_value(name: str, action) -> str:
    """A command-line value of setting `name` that is not its default."""
    default = RenderSpec.fields_by_name()[name].default
    if action.choices:
        return next(c for c in action.choices if c != default)
    if name == "sensor":
        return "40x30"
    if isinstance(default, int):
        return str(default + 1)
    return "lines" if isinstance(default, str) else "3"


def test_every_render_image_setting_reaches_the_batch_items(tmp_path):
    """Each flag of `render-image` but the output's is a RenderSpec field, and `batch render` given the
    same flag and value puts it in every item's settings (the seed: the base each item's derives from)."""
    from solas_mi.batch.commands import _render_spec
    from solas_mi.batch.render import plan_render, seed_of
    from solas_mi.cli import build_parser
    from solas_mi.render.commands import IMAGE_SETTINGS

    parser = build_parser()
    image_cmd, batch_cmd = _subparser(parser, "render-image"), _subparser(parser, "batch", "render")
    flags = {
        a.dest: a for a in image_cmd._actions if a.option_strings and a.dest not in OUTPUT_FLAGS | RECORDED | LENS_FLAGS
    }
    assert set(flags) <= set(RenderSpec.fields_by_name()) and set(flags) == set(IMAGE_SETTINGS)
    assert {a.dest for a in batch_cmd._actions} & {a.dest for a in image_cmd._actions} >= RECORDED
    Image.fromarray(np.full((24, 32), 128, np.uint8)).save(tmp_path / "photo.png")
    for dest, action in flags.items():
        given = [action.option_strings[-1], _other_value(dest, action)]
        wanted = RenderSpec.from_args(
            image_cmd.parse_args(["solas-doublet", "photo.png", "-o", "x.exr", *given]), IMAGE_SETTINGS
        )
        assert getattr(wanted, dest) != getattr(RenderSpec(), dest), dest
        args = batch_cmd.parse_args(
            [str(tmp_path / "photo.png"), "--lens", "solas-doublet", "-o", str(tmp_path / "out"), *given]
        )
        spec, sweep = _render_spec(args)
        (job,) = plan_render(args.inputs, args.output, lens=args.lens, spec=spec, **sweep).jobs
        item = RenderSpec.from_dict(job.params)
        expected = seed_of("photo", wanted.seed) if dest == "seed" else getattr(wanted, dest)
        assert getattr(item, dest) == expected, dest


def test_render_settings_checked_once_and_kept_in_the_manifest_form():
    spec = RenderSpec(sensor="32x24", focus_distance="inf", rings=8)
    assert spec.sensor == (24, 32) and math.isinf(spec.focus_distance)
    assert RenderSpec.from_dict(spec.as_dict()) == spec and spec.as_dict()["focus_distance"] == "inf"
    assert spec.replace(spp=3).spp == 3 and spec.rings == 8
    for bad, message in [
        ({"rings": 0}, "cap rings 0"),
        ({"rings": MAX_RINGS + 1}, f"cap rings {MAX_RINGS + 1}"),
        ({"rings": 8.0}, "cap rings 8.0"),
        ({"spp": True}, "samples per pixel True"),
        ({"boundary": "wrap"}, "boundary 'wrap' must be one of"),
        ({"pitch_um": -1.0}, "pitch_um -1.0 must be a positive number"),
        ({"fov_deg": math.inf}, "fov_deg inf must be a positive number"),
        ({"fov_deg": 180}, "fov_deg 180.0 must be below 180 degrees"),
        ({"variant": "llvm_ad_rgb"}, "RGB variants cannot trace the lens"),
        ({"sensor": (0, 4)}, "sensor (0, 4)"),
        ({"response": ""}, "camera response ''"),
    ]:
        with pytest.raises(SolasError, match=message.replace("(", r"\(").replace(")", r"\)")):
            spec.replace(**bad)
    with pytest.raises(SolasError, match="unknown render setting.*spp_count"):
        spec.replace(spp_count=3)


def test_render_spp_zero_is_refused_not_replaced_by_the_scenes(tmp_path, capsys):
    """`render --spp 0` was the scene's own count in silence: a count of 0 is refused by name."""
    (tmp_path / "sphere.xml").write_text(
        '<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>'
        '<integer name="height" value="6"/></film></sensor><shape type="sphere"/><emitter type="constant"/></scene>'
    )
    assert main(["render", str(tmp_path / "sphere.xml"), "--spp", "0", "-o", str(tmp_path / "x.exr")]) == 2
    assert "samples per pixel 0 must be an integer from 1" in capsys.readouterr().err
    assert not (tmp_path / "x.exr").exists()


@pytest.mark.parametrize(
    "size, extra, shown",
    [
        ("0x0", [], "film is 0x0 px"),
        ("$wx6", ["--set", "w=0"], "film is 0x6 px"),
        ("$wx6", ["--set", "w=0", "--lens", "solas-doublet"], "the scene's film is 0x6 px (after --set)"),
        ("8x0", ["--lens", "solas-doublet"], "the scene's film is 8x0 px (after --set)"),
    ],
)
def test_a_film_without_pixels_is_refused_in_one_line(tmp_path, capsys, size, extra, shown):
    """A scene whose film has no pixels (its own width 0, or `--set width=0`), with or without --lens, ended in
    a ZeroDivisionError traceback (or a message quoting one): refused in one line naming the size."""
    width, height = size.split("x")
    (tmp_path / "s.xml").write_text(
        '<scene version="3.0.0"><default name="w" value="8"/><sensor type="perspective"><film type="hdrfilm">'
        f'<integer name="width" value="{width}"/><integer name="height" value="{height}"/></film></sensor>'
        '<shape type="sphere"/><emitter type="constant"/></scene>'
    )
    assert main(["render", str(tmp_path / "s.xml"), "--spp", "1", *extra, "-o", str(tmp_path / "x.exr")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and shown in err and "must be at least 1 pixel" in err, err
    assert not (tmp_path / "x.exr").exists()


def test_render_image_records_its_camera(tmp_path):
    """render-image says its camera as `render --lens` does: the lens, the sensor it rendered onto (its own
    metadata's size and pitch) and the chosen model's fit to the lens's chief rays over it, at the response's
    one wavelength; a model that cannot hold the field is refused by name before the render, nothing written."""
    from solas_mi import Lens
    from solas_mi.optics.calibration import Sensor, calibrate

    Image.fromarray(np.full((24, 32), 128, np.uint8)).save(tmp_path / "photo.png")
    out = tmp_path / "r.exr"
    assert (
        main(
            [
                "render-image",
                "cooke-triplet",
                str(tmp_path / "photo.png"),
                "--sensor",
                "16x12",
                "--spp",
                "1",
                "--response",
                "mono:550",
                "--calibration-model",
                "woodscape",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    meta = read_exr(out)[1]
    camera, lens = meta["camera"], Lens.load("cooke-triplet")
    assert camera["sensor_px"] == meta["sensor"] == [16, 12] and camera["pitch_um"] == meta["pitch_um"]
    assert camera["lens_hash"] == lens.hash and camera["wavelength_nm"] == 550.0
    (fitted,) = calibrate(lens, "woodscape", Sensor(16, 12, meta["pitch_um"]), [550.0])
    assert camera["calibration"]["parameters"] == pytest.approx(fitted.values, rel=1e-9)
    bad = tmp_path / "bad.exr"
    assert (
        main(
            [
                "render-image",
                "nikkor-fisheye",
                str(tmp_path / "photo.png"),
                "--sensor",
                "16x12",
                "--spp",
                "1",
                "--calibration-model",
                "opencv-pinhole",
                "-o",
                str(bad),
            ]
        )
        == 2
    )
    assert not bad.exists()
