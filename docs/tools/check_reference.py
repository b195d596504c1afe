"""Check that the built site's reference covers the code: the public Python API (every name of
`solas_mi.__all__` and of each subpackage's `__all__`, each package declaring one), every command of the
CLI, every public function and class of every module (solas_mi and its Mitsuba plugins), and every
plugin with its parameter table, an XML and a dict example. Run after `mkdocs build` (reads site/).

    python docs/tools/check_reference.py [SITE]        # default: site
"""

from __future__ import annotations

import ast
import html
import re
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(Path(__file__).resolve().parent))


def api_ids(site: Path) -> set[str]:
    """The anchors of the built API reference page."""
    return set(re.findall(r'id="([\w.]+)"', (site / "reference" / "api" / "index.html").read_text(encoding="utf-8")))


def missing_public(site: Path) -> list[str]:
    """Each name of a package's `__all__` without its entry on the API page ("package.name (where it is
    defined)"), each package without `__all__`, and each name of an `__all__` that nothing defines."""
    from hooks import declared_all, defining_module, packages

    ids, missing = api_ids(site), []
    for package in packages():
        if declared_all(package) is None:
            missing.append(f"{package}: no __all__ (the package's public names)")
        for name in declared_all(package) or []:
            try:
                path = f"{defining_module(package, name)}.{name}"
            except LookupError as exc:
                missing.append(str(exc))
                continue
            if path not in ids:
                missing.append(f"{package}.{name} ({path})")
    return missing


def public_names(path: Path) -> list[str]:
    """The module's public top-level functions and classes (no leading underscore)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [
        node.name
        for node in tree.body
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and not node.name.startswith("_")
    ]


def missing_api(site: Path) -> list[str]:
    from hooks import api_modules, module_file

    ids = api_ids(site)
    return [
        f"{name}.{member}"
        for _, name in api_modules()
        for member in public_names(module_file(name))
        if f"{name}.{member}" not in ids
    ]


def missing_commands(site: Path) -> list[str]:
    from solas_mi.cli import build_parser, iter_commands

    page = html.unescape(
        re.sub(r"<[^>]+>", "", (site / "reference" / "cli" / "index.html").read_text(encoding="utf-8"))
    )
    names = [" ".join(("solas-mi", *path)) for path, _ in iter_commands(build_parser())]
    return [name for name in names if f"usage: {name} " not in page and not page.count(f"usage: {name}\n")]


def missing_plugins(site: Path) -> list[str]:
    from plugins import PLUGINS

    source = (REPO / "docs" / "reference" / "plugins.md").read_text(encoding="utf-8")
    page = (site / "reference" / "plugins" / "index.html").read_text(encoding="utf-8")
    text = " ".join(html.unescape(re.sub(r"<[^>]+>", "", page)).split())
    missing = []
    for name in PLUGINS:
        doc = " ".join(
            re.sub(
                r"[`*]", "", ast.get_docstring(ast.parse((REPO / "plugins" / f"{name}.py").read_text())) or ""
            ).split()
        )
        wants = {
            "section": f"## `{name}`" in source,
            "parameter table": f"::: plugins.{name}" in source,
            "XML example": re.search(rf'```xml\n<\w+ type="{name}"', source) is not None,
            "dict example": re.search(rf'```python\n(?:.*\n)*?\w+ = \{{\s*"type": "{name}"', source) is not None,
            "its documentation rendered": bool(doc) and doc[:60] in text,
        }
        missing += [f"{name}: {what}" for what, ok in wants.items() if not ok]
    return missing


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    site = REPO / (args[0] if args else "site")
    if not (site / "reference" / "api" / "index.html").is_file():
        print(f"{site}: no built site (run mkdocs build first)")
        return 1
    problems = {
        "public API (names of an __all__ without their entry)": missing_public(site),
        "API (public functions and classes without an entry)": missing_api(site),
        "CLI (commands without their help)": missing_commands(site),
        "plugins": missing_plugins(site),
    }
    for what, names in problems.items():
        for name in names:
            print(f"  FAIL {what}: {name}")
    print("reference: " + ", ".join(f"{what.split(' ')[0]} {len(names)} missing" for what, names in problems.items()))
    return 1 if any(problems.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
