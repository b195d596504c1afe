"""Every help text states its default, and the help of every command renders."""
import argparse

import pytest

from solas_mi.cli import build_parser, iter_commands

COMMANDS = list(iter_commands(build_parser()))


def test_every_command_is_walked():
    names = {" ".join(path) for path, _ in COMMANDS}
    assert {"lens list", "lens info", "psf", "psf-grid", "degrade", "render", "render-image", "experiment street",
            "batch degrade", "batch render"} <= names


@pytest.mark.parametrize("path,parser", COMMANDS, ids=[" ".join(p) or "solas-mi" for p, _ in COMMANDS])
def test_defaults_are_in_the_help(path, parser):
    help_text = parser.format_help()
    for action in parser._actions:
        if not action.option_strings or action.default in (None, False, argparse.SUPPRESS) or action.help is None:
            continue
        text = parser.formatter_class(parser.prog)._get_help_string(action)
        assert "default" in text.lower(), f"{' '.join(path)} {action.option_strings[0]}: {action.help!r}"
    assert help_text.startswith("usage: solas-mi")


@pytest.mark.parametrize("path,parser", COMMANDS, ids=[" ".join(p) or "solas-mi" for p, _ in COMMANDS])
def test_every_option_says_what_it_does(path, parser):
    """No option or argument without a help text (`sfr-target --shape` and `lens info --json` had none)."""
    silent = [action.option_strings[0] if action.option_strings else action.dest for action in parser._actions
              if not action.help and not isinstance(action, argparse._SubParsersAction)]
    assert not silent, f"{' '.join(path)}: {', '.join(silent)} without help"
