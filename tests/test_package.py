"""The package's structure: stages import only downward, no import circle (imports inside
functions included, and imports of a module named by a string: importlib, __import__, registries),
light modules stay light, no module over 400 lines."""

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MAX_LINES = 400
# Each stage may import itself, the stages before it in this order's groups, and the shared base.
BASE = {
    "errors",
    "interrupts",
    "lazy",
    "options",
    "resources",
    "llvm",
    "imageio",
    "jsonio",
    "outputs",
    "budget",
    "blas",
    "cores",
    "pages",
    "progress",
    "userfiles",
    "registry",
    "labelkinds",
    "caches",
}
ALLOWED = {
    "optics": set(),
    "psf": {"optics"},
    "convolution": {"optics", "psf"},
    "render": {"optics", "psf"},  # the Mitsuba plugins (plugins/, installed as solas_mi.plugins) are part of it
    "sensor": {"render"},  # irradiance → RAW, after the engines: reads an RGB image as a spectrum as the render does
    "isp": {"sensor"},  # RAW → 8-bit frame: the image processor, after the sensor
    "metrics": set(),
    "analysis": {"optics", "psf", "metrics"},  # the lens analyses: MTF, aberration plots, reports
    "validation": {"optics", "psf", "convolution", "render", "sensor", "isp", "metrics"},
    "batch": {"optics", "psf", "convolution", "render", "sensor", "isp", "metrics"},
    "experiments": {"optics", "psf", "convolution", "render", "sensor", "isp", "metrics", "validation"},
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


IMPORTERS = {"import_module", "__import__"}  # importlib.import_module(name, package), __import__(name, ..., level)
MODULE_STRING = re.compile(r"(\.+|solas_mi\.)[A-Za-z_][\w.]*")  # ".fraunhofer", "..render.psf", "solas_mi.x.y"


def resolve(text: str, package: str) -> str:
    """The absolute name of module `text` (relative when it starts with dots, as importlib resolves it)
    seen from `package`."""
    dots = len(text) - len(text.lstrip("."))
    if not dots:
        return text
    base = package.split(".")[: len(package.split(".")) - dots + 1]
    return ".".join([*base, text[dots:]]) if text[dots:] else ".".join(base)


def _relative_to(call: ast.Call, package: str, name: str) -> tuple[str, str | None]:
    """The name a call of `import_module`/`__import__` imports, made relative (leading dots) where
    `__import__`'s level says so, and the package a relative name is resolved against: a string
    literal, `__package__` or `__name__` (None when the code does not say which)."""
    text = call.args[0].value
    args = {**dict(enumerate(call.args)), **{k.arg: k.value for k in call.keywords}}
    if call_name(call) == "__import__":
        level = args.get(4, args.get("level"))
        return ("." * level.value + text if isinstance(level, ast.Constant) and level.value else text), package
    arg = args.get(1, args.get("package"))
    if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
        return text, arg.value
    return text, {"__package__": package, "__name__": name}.get(getattr(arg, "id", None))


def call_name(call: ast.Call) -> str | None:
    f = call.func
    return f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else None


def imports_of(name: str, source: str, mods, is_package: bool = False) -> set[str]:
    """The package modules that module `name` (code `source`) imports, at any depth of its code: import
    statements, `importlib.import_module`/`__import__` of a string, and module names written as strings
    (a registry's ".fraunhofer" or "..render.psf", resolved as `import_module(text, __package__)` would)."""
    package = name if is_package else name.rpartition(".")[0]
    here = package.split(".")
    targets, read = set(), set()  # read: the names of import calls, resolved with their own package
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            targets |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = ".".join(here[: len(here) - node.level + 1]) if node.level else ""
            source_module = ".".join(p for p in (base, node.module or "") if p)
            targets |= {
                f"{source_module}.{a.name}" if f"{source_module}.{a.name}" in mods else source_module
                for a in node.names
            }
        elif (
            isinstance(node, ast.Call)
            and call_name(node) in IMPORTERS
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
        ):
            text, against = _relative_to(node, package, name)
            read.add(id(node.args[0]))
            if against is not None or not text.startswith("."):
                targets.add(resolve(text, against or package))
        elif (
            isinstance(node, ast.Constant)
            and isinstance(node.value, str)
            and MODULE_STRING.fullmatch(node.value)
            and id(node) not in read
        ):
            targets.add(resolve(node.value, package))
    return {t for t in targets if t in mods and t != name}


def import_graph() -> dict[str, set[str]]:
    """Module → the package modules it imports (`imports_of`)."""
    mods = modules()
    return {name: imports_of(name, path.read_text(), mods, path.name == "__init__.py") for name, path in mods.items()}


def stage(module: str) -> str:
    parts = module.split(".")
    if len(parts) == 1:
        return "solas_mi"
    return "render" if parts[1] == "plugins" else parts[1]


def find_circle(graph: dict[str, set[str]]) -> list[str] | None:
    """An import circle of `graph` (module → modules it imports) as a path back to its start, or None."""
    done, path = set(), []

    def visit(node):
        if node in path:
            return path[path.index(node) :] + [node]
        if node in done:
            return None
        path.append(node)
        for nxt in sorted(graph[node]):
            if circle := visit(nxt):
                return circle
        path.pop()
        done.add(node)
        return None

    return next((c for node in sorted(graph) if (c := visit(node))), None)


def test_no_import_circle():
    circle = find_circle(import_graph())
    assert circle is None, "import circle: " + " -> ".join(circle)


def test_the_graph_sees_imports_inside_functions():
    """The checker must count an import written inside a function (render → plugins happens there)."""
    assert "solas_mi.plugins" in import_graph()["solas_mi.render.mitsuba"]


def test_a_circle_closed_inside_a_function_is_found():
    """Two modules importing each other, one of them only when a function runs: still a circle."""
    mods = {"solas_mi.psf.a", "solas_mi.psf.b"}
    graph = {
        "solas_mi.psf.a": imports_of("solas_mi.psf.a", "from . import b\n", mods),
        "solas_mi.psf.b": imports_of("solas_mi.psf.b", "def f():\n    from .a import g\n    return g\n", mods),
    }
    assert find_circle(graph) == ["solas_mi.psf.a", "solas_mi.psf.b", "solas_mi.psf.a"]


@pytest.mark.parametrize(
    "code",
    [
        "import importlib\ndef f():\n    return importlib.import_module('..render.psf', __package__)\n",
        "from importlib import import_module\nm = import_module('.psf', 'solas_mi.render')\n",
        "m = __import__('solas_mi.render.psf')\n",
        "m = __import__('render.psf', globals(), locals(), ['compute'], 2)\n",
        "METHODS = {'render': Method('render', '..render.psf', 'rays')}\n",  # a registry's module string
        "NAMES = {'psf': 'solas_mi.render.psf'}\n",
    ],
)
def test_the_graph_sees_modules_named_by_strings(code):
    """importlib/__import__ of a string, relative ones resolved against the calling module's package,
    and module names in registries (imported later by `import_module(text, __package__)`)."""
    mods = {"solas_mi.psf.registry", "solas_mi.render.psf"}
    assert imports_of("solas_mi.psf.registry", code, mods) == {"solas_mi.render.psf"}


def test_strings_that_name_no_module_are_no_edge():
    code = "A = '.exr'\nB = 'solas_mi.imageio.read_image or srgb_decode'\nC = '..'\nD = 'psf'\n"
    assert imports_of("solas_mi.psf.registry", code, {"solas_mi.psf.registry", "solas_mi.psf", "solas_mi"}) == set()


def test_a_package_resolves_relative_strings_against_itself():
    """`lazy_exports(__name__, {"Lens": ".lens"})` in optics/__init__.py names solas_mi.optics.lens."""
    assert "solas_mi.optics.lens" in import_graph()["solas_mi.optics"]


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


@pytest.mark.parametrize(
    "module, heavy",
    [
        ("solas_mi.cli", ("drjit", "mitsuba", "matplotlib")),
        ("solas_mi.registry", ("numpy", "drjit", "mitsuba", "matplotlib")),  # the CLI builds its choices from it
        ("solas_mi.labelkinds", ("numpy", "drjit", "mitsuba", "matplotlib")),  # and its label kinds' help
        ("solas_mi.psf.base", ("drjit", "mitsuba", "matplotlib")),
        ("solas_mi.psf.methods", ("drjit", "mitsuba", "matplotlib")),
        ("solas_mi.render.commands", ("drjit", "mitsuba", "matplotlib")),
        ("solas_mi.render.response", ("drjit", "mitsuba", "matplotlib")),
        ("solas_mi.sensor.commands", ("numpy", "OpenEXR", "drjit", "mitsuba")),
        ("solas_mi.isp.commands", ("numpy", "OpenEXR", "colour_demosaicing", "drjit", "mitsuba")),
        ("solas_mi.isp.demosaic", ("colour_demosaicing", "colour", "scipy")),
        ("solas_mi.metrics.commands", ("scipy", "skimage", "matplotlib")),
        ("solas_mi.batch.commands", ("dask", "distributed", "tqdm", "drjit", "matplotlib")),
        ("solas_mi", ("drjit", "mitsuba", "matplotlib", "numpy")),
    ],
)
def test_light_modules_stay_light(module, heavy):
    code = f"import sys, {module}; print(','.join(m for m in {heavy!r} if m in sys.modules))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == "", f"importing {module} loads {loaded}"


def test_building_the_command_line_stays_light():
    code = (
        "import sys; from solas_mi.cli import build_parser; build_parser(); "
        "print(','.join(m for m in ('drjit', 'mitsuba', 'matplotlib', 'dask', 'tqdm') if m in sys.modules))"
    )
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
