"""MkDocs hooks: pages generated from the code at every build, so that they cannot go stale.

- reference/cli.md: every command's help, walked from `solas_mi.cli.build_parser()`;
- reference/api.md: a mkdocstrings section for every module of the solas_mi package (its public
  functions and classes, from their docstrings; read statically, nothing is imported);
- reference/registries.md: every registry's table (`solas_mi.registry.Registry.describe`): the methods,
  formats and layers by name, with summaries, options and references;
- in any page, `{{ names MODULE.REGISTRY }}` becomes that registry's names ("a, b, c"),
  `{{ default MODULE.REGISTRY }}` its default and `{{ table MODULE.REGISTRY }}` its table: the lists of
  names a page shows are the code's.
"""
from __future__ import annotations

import ast
import importlib
import os
import re
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


def registries() -> dict[str, object]:
    """Every registry of the package, "module.NAME" → `Registry`: each module-level `NAME = Registry(...)`
    found in the source, its module imported (which registers its entries; the command line's modules
    are imported first, so that a later stage's entries in a lower stage's registry are there too)."""
    from solas_mi.cli import build_parser

    build_parser()
    found = {}
    for path in sorted((REPO / "solas_mi").rglob("*.py")):
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            call = node.value if isinstance(node, (ast.Assign, ast.AnnAssign)) else None
            if isinstance(call, ast.Call) and getattr(call.func, "id", None) == "Registry":
                parts = path.relative_to(REPO).with_suffix("").parts
                module = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                for target in targets:
                    found[f"{module}.{target.id}"] = getattr(importlib.import_module(module), target.id)
    return found


def registries_reference() -> str:
    """Markdown of every registry's table, in the order of the package's stages."""
    parts = ["# Methods, formats and layers\n",
             "Generated from the registries at every build of this site (`solas_mi.registry.Registry`): every "
             "list of names the package takes, each name with what it does, its own options and a reference. A "
             "new entry is one `register` call ([extending](../develop/extending.md)).\n"]
    for name, registry in registries().items():
        default = f" Default: `{registry.default}`." if registry.default else ""
        parts.append(f"## {registry.kind[0].upper()}{registry.kind[1:]}s\n\n`{name}`.{default}\n\n"
                     f"{registry.describe()}\n")
    return "\n".join(parts)


MARKER = re.compile(r"\{\{\s*(names|table|default)\s+(solas_mi\.[\w.]+)\s*\}\}")


def fill_markers(markdown: str) -> str:
    """`markdown` with each `{{ names|default|table MODULE.REGISTRY }}` replaced by the registry's names,
    default or table; an unknown registry is an error (the build stops)."""
    def fill(match: re.Match) -> str:
        module, _, attr = match[2].rpartition(".")
        registry = getattr(importlib.import_module(module), attr)
        return {"names": ", ".join(registry), "default": registry.default, "table": registry.describe()}[match[1]]

    return MARKER.sub(fill, markdown)


def on_files(files, config):
    pages = (("reference/cli.md", cli_reference()), ("reference/api.md", api_reference()),
             ("reference/registries.md", registries_reference()))
    for uri, content in pages:
        files.append(File.generated(config, uri, content=content))
    return files


def on_page_markdown(markdown, page, config, files):
    return fill_markers(markdown)
