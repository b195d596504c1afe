"""MkDocs hooks: pages generated from the code at every build, so that they cannot go stale.

- reference/cli.md: every command's help, walked from `solas_mi.cli.build_parser()`;
- reference/api.md: a mkdocstrings section for every module of the solas_mi package (its public
  functions and classes, from their docstrings; read statically, nothing is imported).
"""
from __future__ import annotations

import os
from pathlib import Path

from mkdocs.structure.files import File

REPO = Path(__file__).resolve().parents[2]
# modules documented elsewhere or with nothing public
API_SKIP = {"solas_mi.__main__"}


def cli_reference() -> str:
    """Markdown of every command's --help, in the order of `solas-mi --help`."""
    os.environ["COLUMNS"] = "100"  # the help's width, the same on every machine
    from solas_mi.cli import build_parser, iter_commands

    parts = ["# Command-line reference\n",
             "Generated from the argument parsers at every build of this site: each section is the command's "
             "`--help`. Defaults are stated in each option's text.\n"]
    for path, parser in iter_commands(build_parser()):
        name = " ".join(("solas-mi", *path))
        parts.append(f"## {name}\n\n```text\n{parser.format_help().rstrip()}\n```\n")
    return "\n".join(parts)


def api_modules() -> list[tuple[str, str]]:
    """(installed name, name in the source tree) of every module of solas_mi, the Mitsuba plugins
    (plugins/, installed as solas_mi.plugins) last."""
    names = []
    for folder, installed in (("solas_mi", "solas_mi"), ("plugins", "solas_mi.plugins")):
        for path in sorted((REPO / folder).rglob("*.py")):
            parts = path.relative_to(REPO).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            if name not in API_SKIP:
                names.append((installed + name[len(folder):], name))
    return names


def api_reference() -> str:
    parts = ["# Python API reference\n",
             "Generated from the docstrings of every module at each build. The stages follow the data: "
             "optics → psf → convolution; optics → render; images → metrics; validation, batch and "
             "experiments on top ([package layout](../develop/layout.md)). Start with `solas_mi.Lens`, "
             "`solas_mi.psf.psf`, `solas_mi.psf.psf_grid`, `solas_mi.convolution.methods.degrade` and "
             "`solas_mi.mitsuba`.\n"]
    for installed, name in api_modules():
        parts.append(f"## `{installed}`\n\n::: {name}\n    options:\n      show_root_heading: false\n")
    return "\n".join(parts)


def on_files(files, config):
    for uri, content in (("reference/cli.md", cli_reference()), ("reference/api.md", api_reference())):
        files.append(File.generated(config, uri, content=content))
    return files
