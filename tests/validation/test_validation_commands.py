"""`solas-mi crossval` and `solas-mi report error-vs-time` (`solas_mi.validation.commands`)."""

import argparse

import pytest

from solas_mi.errors import SolasError
from solas_mi.options import positive_ints
from solas_mi.validation import commands


def test_commands_register_and_parse():
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="command")
    commands.register(sub)
    a = parser.parse_args(["crossval", "solas-doublet", "img.png", "-o", "d", "--scale", "0.25", "--spp", "96"])
    assert a.run is commands.run_crossval and a.spp == 96 and a.scale == 0.25
    a = parser.parse_args(["report", "error-vs-time", "solas-doublet", "img.png", "-o", "d", "--sensor", "320x240"])
    assert a.run is commands.run_error_vs_time and a.sensor == "320x240"
    assert commands.block_grids("4x3,64x48", "--interp-grids") == ((4, 3), (64, 48))
    with pytest.raises(SystemExit):
        parser.parse_args(["crossval", "solas-doublet", "img.png", "-o", "d", "--scale", "0.5", "--sensor", "8x8"])


def test_bad_values_are_a_solas_error():
    with pytest.raises(SolasError, match="comma-separated"):
        positive_ints("3,x", "--spp")


def test_the_steps_of_a_long_run_go_to_stderr(capsys):
    """stdout holds the results (the tables that benchmarks/run_all.py records), the steps stderr."""
    commands._say("crossval: reference noise 0.2 % of RMS")
    out, err = capsys.readouterr()
    assert out == "" and err == "crossval: reference noise 0.2 % of RMS\n"


def test_error_maps_label_their_axes_and_scale(tmp_path, monkeypatch):
    """The heat maps of crossval and the street experiment, read from the figure as it is saved: image
    axes in pixels, the colour scale in per cent of the reference's RMS."""
    import numpy as np
    from matplotlib.figure import Figure

    from solas_mi.validation.crossval import heat_png

    saved = []
    save = Figure.savefig
    monkeypatch.setattr(Figure, "savefig", lambda fig, *a, **k: (saved.append(fig), save(fig, *a, **k))[1])
    heat_png(tmp_path / "e.png", np.full((24, 32), 0.01), "case: |image − reference| / RMS(reference)")
    image, scale = saved[0].axes
    assert (image.get_xlabel(), image.get_ylabel()) == ("x (px)", "y (px)") and image.get_title().startswith("case")
    assert scale.get_ylabel() == "error, % of the reference's RMS"
    assert (tmp_path / "e.png").is_file()


@pytest.mark.parametrize(
    "text, says",
    [
        ("", "--cases '' selects no case"),
        (" , ", "--cases ' , ' selects no case"),
        ("interp:geometric:4x3,", "has an empty entry"),
    ],
)
def test_an_empty_case_selection_is_refused(monkeypatch, capsys, tmp_path, text, says):
    """`--cases ''` ran every default case; an empty selection is an error naming it, before any work."""
    from solas_mi.cli import main
    from solas_mi.resources import resource_dir

    def ran(*args, **kwargs):
        raise AssertionError(f"crossval ran the cases {args[5]}")

    monkeypatch.setattr(commands, "crossval", ran)
    image = resource_dir("scenes") / "images" / "rocket.png"
    assert main(["crossval", "solas-doublet", str(image), "-o", str(tmp_path / "cv"), "--cases", text]) == 2
    err = capsys.readouterr().err
    assert says in err and ",".join(commands.DEFAULT_CASES) in err and err.count("\n") == 1, err
    assert not (tmp_path / "cv").exists()
