"""The package's structure: stages import only downward, no import circle (imports inside
functions included), light modules stay light, no module over 400 lines."""
import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MAX_LINES = 400
# Each stage may import itself, the stages before it in this order's groups, and the shared base.
BASE = {"errors", "lazy", "options", "resources", "llvm", "imageio", "outputs", "budget", "blas"}
ALLOWED = {
    "optics": set(),
    "psf": {"optics"},
    "convolution": {"optics", "psf"},
    "render": {"optics", "psf"},  # the Mitsuba plugins (plugins/, installed as solas_mi.plugins) are part of it
    "metrics": set(),
    "validation": {"optics", "psf", "convolution", "render", "metrics"},
    "batch": {"optics", "psf", "convolution", "render", "metrics"},
    "experiments": {"optics", "psf", "convolution", "render", "metrics", "validation"},
}


def modules() -> dict[str, Path]:
    """Module name → file, for solas_mi/ and plugins/ (installed as solas_mi.plugins)."""
    found = {}
    for base, package in ((ROOT / "solas_mi", "solas_mi"), (ROOT / "plugins", "solas_mi.plugins")):
        for path in base.rglob("*.py"):
            parts = list(path.relative_to(base).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            found[".".join([package, *parts])] = path
    return found


def import_graph() -> dict[str, set[str]]:
    """Module → the package modules it imports, at any depth of its code."""
    mods = modules()
    graph = {}
    for name, path in mods.items():
        is_package = path.name == "__init__.py"
        here = name.split(".") if is_package else name.split(".")[:-1]
        edges = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = ".".join(here[: len(here) - node.level + 1]) if node.level else ""
                source = ".".join(p for p in (base, node.module or "") if p)
                targets = [f"{source}.{a.name}" if f"{source}.{a.name}" in mods else source for a in node.names]
            else:
                continue
            edges |= {t for t in targets if t in mods and t != name}
        graph[name] = edges
    return graph


def stage(module: str) -> str:
    parts = module.split(".")
    if len(parts) == 1:
        return "solas_mi"
    return "render" if parts[1] == "plugins" else parts[1]


def test_no_import_circle():
    graph = import_graph()
    done, path = set(), []

    def visit(node):
        if node in path:
            cycle = path[path.index(node):] + [node]
            pytest.fail("import circle: " + " -> ".join(cycle))
        if node in done:
            return
        path.append(node)
        for nxt in sorted(graph[node]):
            visit(nxt)
        path.pop()
        done.add(node)

    for node in sorted(graph):
        visit(node)


def test_the_graph_sees_imports_inside_functions():
    """The checker must count an import written inside a function (render → plugins happens there)."""
    assert "solas_mi.plugins" in import_graph()["solas_mi.render.mitsuba"]


def test_stages_import_only_downward():
    bad = []
    for module, targets in import_graph().items():
        src = stage(module)
        if src not in ALLOWED:
            continue
        for t in targets:
            dst = stage(t)
            if dst not in BASE and dst != src and dst not in ALLOWED[src]:
                bad.append(f"{module} -> {t}")
    assert not bad, "a stage imports a later one: " + ", ".join(sorted(bad))


@pytest.mark.parametrize("module, heavy", [
    ("solas_mi.cli", ("drjit", "mitsuba", "matplotlib")),
    ("solas_mi.psf.base", ("drjit", "mitsuba", "matplotlib")),
    ("solas_mi.psf.methods", ("drjit", "mitsuba", "matplotlib")),
    ("solas_mi.render.commands", ("drjit", "mitsuba", "matplotlib")),
    ("solas_mi.render.response", ("drjit", "mitsuba", "matplotlib")),
    ("solas_mi.metrics.commands", ("scipy", "skimage", "matplotlib")),
    ("solas_mi.batch.commands", ("dask", "distributed", "tqdm", "drjit", "matplotlib")),
    ("solas_mi", ("drjit", "mitsuba", "matplotlib", "numpy")),
])
def test_light_modules_stay_light(module, heavy):
    code = f"import sys, {module}; print(','.join(m for m in {heavy!r} if m in sys.modules))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == "", f"importing {module} loads {loaded}"


def test_building_the_command_line_stays_light():
    code = ("import sys; from solas_mi.cli import build_parser; build_parser(); "
            "print(','.join(m for m in ('drjit', 'mitsuba', 'matplotlib', 'dask', 'tqdm') if m in sys.modules))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == "", f"building the parser loads {loaded}"


def test_no_module_over_the_limit():
    long = {name: n for name, path in modules().items() if (n := len(path.read_text().splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def test_lazy_exports():
    import solas_mi
    from solas_mi import psf as psf_package

    assert solas_mi.Lens.__name__ == "Lens" and callable(solas_mi.paraxial) and callable(solas_mi.spot)
    assert callable(psf_package.psf) and callable(psf_package.psf_grid) and psf_package.PSFGrid.__name__ == "PSFGrid"
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        solas_mi.nothing  # noqa: B018
