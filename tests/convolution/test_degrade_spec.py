"""`DegradeSpec` (convolution.spec): every option of degrading images, checked once when built; each
flag of `degrade` and `batch degrade` sets its field; `degrade_file` degrades as the spec says."""

import argparse
import re

import numpy as np
import pytest

from solas_mi.batch.commands import _degrade_spec
from solas_mi.cli import build_parser
from solas_mi.convolution.commands import DEGRADE_OPTIONS
from solas_mi.convolution.methods import METHODS
from solas_mi.convolution.spec import DegradeSpec
from solas_mi.errors import SolasError
from solas_mi.optics.frame import FrameCamera


@pytest.mark.parametrize(
    "given, message",
    [
        ({"method": "fft"}, f"convolution method 'fft' must be one of {', '.join(METHODS.names())}"),
        ({"boundary": "wrap"}, "boundary 'wrap' must be one of edge, reflect, zero"),
        ({"linear": "yes"}, "linear 'yes' must be True or False"),
        ({"output_format": "png8"}, "output format 'png8' must be one of exr, exr-half, png16"),
        ({"occlusion": "z"}, "occlusion 'z' must be one of filled, layered, none"),
        ({"silhouette": None}, "silhouette None must be one of nearest, as-given"),
        ({"depth_pattern": "depth.exr"}, "depth pattern 'depth.exr' must be a file name with {stem} ending in .exr"),
        ({"depth_pattern": "d/{stem}.exr"}, "depth pattern 'd/{stem}.exr' must be a file name"),
        ({"scale_lens": 0}, "scale_lens 0 must be the camera's pixel pitch, a positive number of µm"),
        ({"scale_lens": "5"}, "scale_lens '5' must be the camera's pixel pitch"),
        ({"scale_lens": float("nan")}, "scale_lens nan must be the camera's pixel pitch"),
        (
            {"label_patterns": "instance=ids.png"},
            "label patterns: instance file 'ids.png' must be a file name with {stem}",
        ),
        ({"label_patterns": {"colour": "{stem}.png"}}, "label patterns: colour={stem}.png must be KIND=FILE with KIND"),
        ({"frame": "pinhole"}, "frame 'pinhole' must be a solas_mi.optics.frame.FrameCamera"),
        ({"grid_spec": {"grid": (8, 8)}}, "grid_spec {'grid': (8, 8)} must be a solas_mi.psf.spec.GridSpec"),
    ],
)
def test_bad_options_are_refused_by_name(given, message):
    with pytest.raises(SolasError, match=re.escape(message)) as err:
        DegradeSpec(**given)
    assert "\n" not in str(err.value)


def _subparser(*names):
    parser = build_parser()
    for name in names:
        parser = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[name]
    return parser


def _other_text(name: str, action) -> str:
    """A command-line value of DegradeSpec field `name` that is not its default."""
    default = DegradeSpec.fields_by_name()[name].default
    if action.choices:
        return next(c for c in action.choices if c != default)
    return {
        "depth_pattern": "{stem}_z.exr",
        "scale_lens": "3.5",
        "label_patterns": "instance={stem}_ids.png",
        "ghost_threshold": "250",
    }[name]


# the flags another flag goes with: the ghost threshold is refused without --ghosts
WITH = {"ghost_threshold": ("ghosts", ["--ghosts"])}


@pytest.mark.parametrize(
    "command, base, build",
    [
        (
            ("degrade",),
            ["in.png", "--psf-grid", "g.exr", "-o", "o.exr"],
            lambda args: DegradeSpec.from_args(args, DEGRADE_OPTIONS),
        ),
        (("batch", "degrade"), ["in.png", "--psf-grid", "g.exr", "-o", "out"], _degrade_spec),
    ],
)
def test_every_flag_sets_its_spec_field(command, base, build):
    """Each flag of the command that is a DegradeSpec field, given a value other than its default, sets
    that field (and only it); not given, the spec's default holds."""
    parser = _subparser(*command)
    flags = DegradeSpec.flags()
    dests = {flag.dest: name for name, flag in flags.items()}
    taken = {dests[a.dest]: a for a in parser._actions if a.dest in dests}
    assert set(taken) >= set(DEGRADE_OPTIONS) and set(taken) <= set(flags)
    default = build(parser.parse_args(base))
    assert default == DegradeSpec()
    for name, action in taken.items():
        extra = [action.option_strings[0]] + (
            [] if isinstance(action, argparse._StoreTrueAction) else [_other_text(name, action)]
        )
        other, flag = WITH.get(name, (None, []))
        spec = build(parser.parse_args([*base, *flag, *extra]))
        changed = {f for f in DegradeSpec.fields_by_name() if getattr(spec, f) != getattr(default, f)}
        assert changed == {name} | ({other} if other else set()), (name, changed)
        assert getattr(spec, name) == (True if len(extra) == 1 else flags[name].read(extra[1]))


def test_the_degrade_file_follows_its_spec(tmp_path, synthetic):
    """`degrade_file` with a spec writes what `degrade` computes with the spec's options, bit for bit, and
    states them."""
    from solas_mi.convolution.methods import degrade
    from solas_mi.convolution.output import degrade_file
    from solas_mi.imageio import read_exr, read_image, write_png

    g = synthetic.make_grid(
        np.broadcast_to(synthetic.gaussian(15, 8.0, 2.0), (3, 4, 4, 15, 15)), 2.0, wavelengths=(656, 531, 486)
    )
    g.write(str(tmp_path / "grid.exr"))
    write_png(tmp_path / "in.png", np.random.default_rng(1).random((48, 64, 3)))
    frame = FrameCamera("fov", fov_deg=1.5)
    spec = DegradeSpec(method="patch", boundary="zero", linear=True, frame=frame)
    meta = degrade_file(tmp_path / "in.png", g, tmp_path / "grid.exr", tmp_path / "o.exr", tmp_path / "o.png", spec)
    expected = degrade(read_image(tmp_path / "in.png", linearize=False), g, "patch", "zero", frame=frame)
    channels, written = read_exr(tmp_path / "o.exr")
    assert np.array_equal(np.stack([channels[c] for c in "RGB"], axis=-1), expected)
    assert (written["method"], written["boundary"], written["input_encoding"]) == ("patch", "zero", "linear")
    assert written["frame_camera"] == frame.meta(64, 48) and meta["output_format"] == "exr"
    with pytest.raises(SolasError, match="spec 'patch' must be a solas_mi.convolution.spec.DegradeSpec"):
        degrade_file(tmp_path / "in.png", g, tmp_path / "grid.exr", tmp_path / "p.exr", tmp_path / "p.png", "patch")
    assert not (tmp_path / "p.exr").exists()
