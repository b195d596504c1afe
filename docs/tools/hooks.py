"""MkDocs hooks: pages generated from the code at every build, so that they cannot go stale.

- reference/cli.md: every command's help, walked from `solas_mi.cli.build_parser()`;
- reference/api.md: the public Python API first — every name of `solas_mi.__all__` and of each
  subpackage's `__all__` (`public_api`), documented where it is defined, its docstring in numpydoc style —
  then a mkdocstrings section for every module of the package and its Mitsuba plugins (the module's other
  functions and classes; read statically, nothing is imported);
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
from functools import cache
from pathlib import Path

from mkdocs.structure.files import File

REPO = Path(__file__).resolve().parents[2]
# modules documented elsewhere or with nothing public
API_SKIP = {"solas_mi.__main__"}


def cli_reference() -> str:
    """Markdown of every command's --help, in the order of `solas-mi --help`."""
    os.environ["COLUMNS"] = "100"  # the help's width, the same on every machine
    from solas_mi.cli import build_parser, iter_commands

    parts = [
        "# Command-line reference\n",
        "Generated from the argument parsers at every build of this site: each section is the command's "
        "`--help`. Defaults are stated in each option's text.\n",
    ]
    for path, parser in iter_commands(build_parser()):
        name = " ".join(("solas-mi", *path))
        parts.append(f"## {name}\n\n```text\n{parser.format_help().rstrip()}\n```\n")
    return "\n".join(parts)


def module_name(path: Path) -> str:
    """The dotted name of a module of the source tree (a package's `__init__.py`: the package)."""
    parts = path.relative_to(REPO).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def module_file(name: str) -> Path:
    """The source file of module `name` (solas_mi.x.y or plugins.x)."""
    base = REPO.joinpath(*name.split("."))
    return base / "__init__.py" if base.is_dir() else base.with_suffix(".py")


@cache
def module_tree(name: str) -> ast.Module:
    """The parsed source of module `name`."""
    return ast.parse(module_file(name).read_text(encoding="utf-8"))


def api_modules() -> list[tuple[str, str]]:
    """(installed name, name in the source tree) of every module of solas_mi, the Mitsuba plugins
    (plugins/, installed as solas_mi.plugins) last."""
    names = []
    for folder, installed in (("solas_mi", "solas_mi"), ("plugins", "solas_mi.plugins")):
        for path in sorted((REPO / folder).rglob("*.py")):
            name = module_name(path)
            if name not in API_SKIP:
                names.append((installed + name[len(folder) :], name))
    return names


def packages() -> list[str]:
    """Every package of solas_mi (a folder with an `__init__.py`), parents first."""
    return sorted(module_name(path) for path in (REPO / "solas_mi").rglob("__init__.py"))


def declared_all(module: str) -> list[str] | None:
    """The names of the module's `__all__` (a list or tuple of strings at its top level); None without one."""
    for node in module_tree(module).body:
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and "__all__" in [
            getattr(t, "id", None) for t in (node.targets if isinstance(node, ast.Assign) else [node.target])
        ]:
            return [element.value for element in node.value.elts]
    return None


def _absolute(module: str, relative: str, level: int, package: bool) -> str:
    """`relative` (`level` dots) as imported by `module` (a package's relative imports start in itself)."""
    if not level:
        return relative
    parts = module.split(".")[: len(module.split(".")) - level + package]
    return ".".join([*parts, relative] if relative else parts)


def _imported(module: str) -> dict[str, str]:
    """Name → the module it comes from, for each name `module` imports at its top level (`from X import name`)
    or exports lazily (`lazy_exports(__name__, {name: ".x"})`)."""
    found, package = {}, module_file(module).name == "__init__.py"
    for node in module_tree(module).body:
        if isinstance(node, ast.ImportFrom):
            for alias in node.names:
                found[alias.asname or alias.name] = _absolute(module, node.module or "", node.level, package)
        call = getattr(node, "value", None)
        if isinstance(call, ast.Call) and getattr(call.func, "id", None) == "lazy_exports":
            for key, value in zip(call.args[1].keys, call.args[1].values):
                dots = len(value.value) - len(value.value.lstrip("."))
                found[key.value] = _absolute(module, value.value.lstrip("."), dots, package)
    return found


def _defines(module: str, name: str) -> bool:
    """Whether `module`'s top level defines `name` (a function, a class or an assignment)."""
    for node in module_tree(module).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and node.name == name:
            return True
        targets = (
            node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(node, ast.AnnAssign) else []
        )
        if name in [getattr(t, "id", None) for t in targets]:
            return True
    return False


def defining_module(module: str, name: str) -> str:
    """The module that defines `name` as `module` exports it, following its imports and lazy exports; a
    LookupError where the name is neither defined nor imported along the way."""
    if _defines(module, name):
        return module
    source = _imported(module).get(name)
    if source is None or source == module:
        raise LookupError(f"{module}.{name}: neither defined nor imported there")
    return defining_module(source, name)


def public_api() -> dict[str, list[tuple[str, str]]]:
    """The public Python API: package → (name, the module that defines it) for each name of the package's
    `__all__`, every package of solas_mi (a package without `__all__` has none: `check_reference` and the
    docstring test name it)."""
    return {
        package: [(name, defining_module(package, name)) for name in declared_all(package) or []]
        for package in packages()
    }


def public_definitions() -> dict[str, str]:
    """Where each public name is documented: its definition's path ("solas_mi.optics.lens.Lens") → the first
    public path a user imports it by ("solas_mi.Lens")."""
    found: dict[str, str] = {}
    for package, names in public_api().items():
        for name, module in names:
            found.setdefault(f"{module}.{name}", f"{package}.{name}")
    return found


def api_reference() -> str:
    parts = [
        "# Python API reference\n",
        "Generated from the docstrings at each build. First the public API: every name of `solas_mi.__all__` "
        "and of each subpackage's `__all__` (numpydoc: parameters, returns, what it raises, examples run by the "
        "docs build); then every module, with what else it holds. The stages follow the data: "
        "optics → psf → convolution; optics → render → sensor → isp; images → metrics; validation, batch and "
        "experiments on top ([package layout](../develop/layout.md)).\n",
        "## Public API\n",
    ]
    shown: set[str] = set()
    public = public_definitions()
    for package, names in public_api().items():
        if not names:
            continue
        parts.append(f"### `{package}`\n")
        for name, module in names:
            path = f"{module}.{name}"
            if path in shown:
                parts.append(f"- `{package}.{name}`: the same as [`{public[path]}`](#{path})\n")
                continue
            shown.add(path)
            parts.append(
                f'::: {path}\n    options:\n      show_root_heading: true\n      heading: "{package}.{name}"\n'
                f'      toc_label: "{package}.{name}"\n      heading_level: 4\n'
            )
    parts.append("## Modules\n")
    for installed, name in api_modules():
        own = sorted(path for path in public if path.rpartition(".")[0] == name)
        filters = ", ".join(f'"{f}"' for f in ["!^_", *(f"!^{path.rpartition('.')[2]}$" for path in own)])
        links = ", ".join(f"[`{public[path]}`](#{path})" for path in own)
        parts.append(
            f"### `{installed}`\n"
            + (f"\nPublic, documented above: {links}.\n" if own else "")
            + f"\n::: {name}\n    options:\n      show_root_heading: false\n      heading_level: 4\n"
            f"      filters: [{filters}]\n"
        )
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
                module = module_name(path)
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                for target in targets:
                    found[f"{module}.{target.id}"] = getattr(importlib.import_module(module), target.id)
    return found


def registries_reference() -> str:
    """Markdown of every registry's table, in the order of the package's stages."""
    parts = [
        "# Methods, formats and layers\n",
        "Generated from the registries at every build of this site (`solas_mi.registry.Registry`): every "
        "list of names the package takes, each name with what it does, its own options and a reference. A "
        "new entry is one `register` call ([extending](../develop/extending.md)).\n",
    ]
    for name, registry in registries().items():
        default = f" Default: `{registry.default}`." if registry.default else ""
        plural = registry.kind[:-2] + "es" if registry.kind.endswith("is") else registry.kind + "s"  # analysis
        parts.append(f"## {plural[0].upper()}{plural[1:]}\n\n`{name}`.{default}\n\n{registry.describe()}\n")
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
    pages = (
        ("reference/cli.md", cli_reference()),
        ("reference/api.md", api_reference()),
        ("reference/registries.md", registries_reference()),
    )
    for uri, content in pages:
        files.append(File.generated(config, uri, content=content))
    return files


def on_page_markdown(markdown, page, config, files):
    return fill_markers(markdown)
