"""Every help text states its default, and the help of every command renders."""

import argparse

import pytest

from solas_mi.cli import build_parser, iter_commands

COMMANDS = list(iter_commands(build_parser()))


def test_every_command_is_walked():
    names = {" ".join(path) for path, _ in COMMANDS}
    assert {
        "lens list",
        "lens info",
        "psf",
        "psf-grid",
        "degrade",
        "render",
        "render-image",
        "experiment street",
        "batch degrade",
        "batch render",
    } <= names


@pytest.mark.parametrize("path,parser", COMMANDS, ids=[" ".join(p) or "solas-mi" for p, _ in COMMANDS])
def test_defaults_are_in_the_help(path, parser):
    help_text = parser.format_help()
    for action in parser._actions:
        if not action.option_strings or action.default in (None, False, argparse.SUPPRESS) or action.help is None:
            continue
        text = parser.formatter_class(parser.prog)._get_help_string(action)
        assert "default" in text.lower(), f"{' '.join(path)} {action.option_strings[0]}: {action.help!r}"
    assert help_text.startswith("usage: solas-mi")


def test_every_option_has_a_help_text():
    bare = [
        f"{' '.join(path)} {a.option_strings[0]}"
        for path, parser in COMMANDS
        for a in parser._actions
        if a.option_strings and a.help is None
    ]
    assert not bare, f"options without help: {bare}"


def test_every_lens_argument_names_every_lens_file_format():
    """The formats a LENS argument or --lens option lists are those the readers are registered for
    (`optics.formats.READERS`, and our TOML which `Lens.load` reads itself); `lens convert`'s those of the
    writers (`WRITERS`)."""
    from solas_mi.optics.formats import READERS, WRITERS

    readable, lenses = {".toml", *READERS}, []
    for path, parser in COMMANDS:
        for action in parser._actions:
            if action.dest == "lens" and action.help is not None:
                lenses.append(" ".join(path))
                assert all(e in action.help for e in readable), f"{' '.join(path)} {action.dest}: {action.help!r}"
    assert {
        "scene",
        "render",
        "render-image",
        "psf",
        "psf-grid",
        "lens info",
        "crossval",
        "batch degrade",
        "batch render",
    } <= set(lenses)
    convert = dict(COMMANDS)[("lens", "convert")]
    output = next(a for a in convert._actions if a.dest == "output")
    assert all(e in output.help for e in WRITERS) and ".seq" not in WRITERS


def test_one_field_number_means_what_the_help_says():
    """`psf --field-deg 2` is the field (0, 2) and `psf-grid --field-range-deg 2` the half ranges (2, 2):
    each help says what one number means."""
    from solas_mi.psf.commands import _field
    from solas_mi.psf.spec import _range

    helps = {
        (" ".join(path), a.dest): " ".join(a.help.split())
        for path, parser in COMMANDS
        for a in parser._actions
        if a.dest in ("field_deg", "field_range_deg")
    }
    assert _field("2") == (0.0, 2.0) and "one value Y (x = 0)" in helps["psf", "field_deg"]
    assert _range("2") == (2.0, 2.0) and "one value for both" in helps["psf-grid", "field_range_deg"]


def test_png_has_one_meaning():
    """--png is where the preview, always written, goes, in every command that has it (one definition:
    `outputs.add_png_option`); the PSF grid's optional mosaic has a flag of its own."""
    pngs = {" ".join(path): a for path, parser in COMMANDS for a in parser._actions if "--png" in a.option_strings}
    assert {"psf", "degrade", "render", "render-image"} <= set(pngs) and "psf-grid" not in pngs
    assert len({(a.help, a.nargs, a.const, a.default) for a in pngs.values()}) == 1
    assert "always written" in next(iter(pngs.values())).help
    grid = dict(COMMANDS)[("psf-grid",)]
    assert any("--mosaic" in a.option_strings and "default: none" in a.help for a in grid._actions)
