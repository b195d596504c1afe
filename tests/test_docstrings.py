"""The public Python API is documented in one style, numpydoc. Public: every name of `solas_mi.__all__` and
of each subpackage's `__all__` (`docs/tools/hooks.public_api`, which the API reference renders), and the
public methods and properties of its classes. Each has a docstring with a summary line; a function, method
or class that takes parameters has a Parameters section naming each of them and nothing else; one that
returns a value has Returns (Yields for a generator); one that raises SolasError itself says so under
Raises; sections are numpydoc's, underlined, and no other style's headers ("Args:") appear."""

import ast
import importlib
import inspect
import itertools
import re
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "tools"))
import hooks  # noqa: E402

SECTIONS = (
    "Parameters",
    "Other Parameters",
    "Attributes",
    "Returns",
    "Yields",
    "Receives",
    "Raises",
    "Warns",
    "Warnings",
    "See Also",
    "Notes",
    "References",
    "Examples",
    "Methods",
)
OTHER_STYLE = re.compile(r"^\s*(Args|Arguments|Keyword Args|Returns|Yields|Raises|Examples?|Note|Notes):\s*$", re.M)
ENTRY = re.compile(r"^(\*{0,2}[A-Za-z_]\w*(?:\s*,\s*\*{0,2}[A-Za-z_]\w*)*)\s*(?::.*)?$")


def sections(doc: str) -> dict[str, list[str]]:
    """Section name → its lines, of a numpydoc docstring (a section: its name, then a line of dashes as long)."""
    lines, found, current = inspect.cleandoc(doc).splitlines(), {}, None
    for i, line in enumerate(lines):
        if line.strip() in SECTIONS and i + 1 < len(lines) and re.fullmatch(r"-{3,}", lines[i + 1].strip()):
            current = line.strip()
            found[current] = []
        elif current is not None and not re.fullmatch(r"-{3,}", line.strip()):
            found[current].append(line)
    return found


def underlines(doc: str) -> list[str]:
    """Section headers whose underline is not a line of dashes as long as the header."""
    lines = inspect.cleandoc(doc).splitlines()
    return [
        line.strip()
        for i, line in enumerate(lines[:-1])
        if line.strip() in SECTIONS
        and re.fullmatch(r"-+", lines[i + 1].strip())
        and len(lines[i + 1].strip()) != len(line.strip())
    ]


def entries(lines: list[str]) -> set[str]:
    """The names a Parameters section documents: its lines at the section's own indentation."""
    names = set()
    for line in lines:
        if line.strip() and not line.startswith((" ", "\t")):
            match = ENTRY.match(line.strip())
            names |= {n.strip().lstrip("*") for n in match[1].split(",")} if match else {line.strip()}
    return names


def function_node(function) -> ast.FunctionDef | None:
    """The function's definition, parsed; None for one without source (a dataclass's generated __init__)."""
    try:
        return ast.parse(textwrap.dedent(inspect.getsource(function))).body[0]
    except OSError:
        return None


def own_nodes(node):
    """The nodes of a function's body, not those of functions or classes defined inside it."""
    todo = list(node.body)
    while todo:
        child = todo.pop()
        yield child
        if not isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
            todo.extend(ast.iter_child_nodes(child))


def returns_value(node) -> bool:
    return any(
        isinstance(n, ast.Return)
        and n.value is not None
        and not (isinstance(n.value, ast.Constant) and n.value.value is None)
        for n in own_nodes(node)
    )


def yields(node) -> bool:
    return any(isinstance(n, (ast.Yield, ast.YieldFrom)) for n in own_nodes(node))


def raises_solas_error(node) -> bool:
    def named(exc) -> bool:
        return getattr(exc.func if isinstance(exc, ast.Call) else exc, "id", None) == "SolasError"

    return any(isinstance(n, ast.Raise) and n.exc is not None and named(n.exc) for n in own_nodes(node))


def parameters(callable_) -> list[str]:
    """The parameters a caller gives (a method's self or cls left out); none where no signature is known."""
    try:
        signature = inspect.signature(callable_)
    except (TypeError, ValueError):
        return []
    return [name for name in signature.parameters if name not in ("self", "cls")]


def problems(
    doc: str | None, params: list[str], returns: bool = False, yields_: bool = False, raises: bool = False
) -> list[str]:
    """What a docstring lacks, given what its object takes, returns and raises."""
    if not doc or not doc.strip():
        return ["no docstring"]
    found, out = sections(doc), []
    if OTHER_STYLE.search(inspect.cleandoc(doc)):
        out.append("a header of another style (numpydoc: the name, then a line of dashes)")
    out += [f"{header}: its underline is not as long as it" for header in underlines(doc)]
    documented = entries(found.get("Parameters", []) + found.get("Other Parameters", []))
    if params and "Parameters" not in found:
        out.append(f"no Parameters section (takes {', '.join(params)})")
    elif missing := [p for p in params if p not in documented]:
        out.append(f"Parameters does not name {', '.join(missing)}")
    if stray := sorted(documented - set(params)):
        out.append(f"Parameters names {', '.join(stray)}, which it does not take")
    if returns and "Returns" not in found:
        out.append("no Returns section (it returns a value)")
    if yields_ and "Yields" not in found:
        out.append("no Yields section (it is a generator)")
    if raises and "SolasError" not in "\n".join(found.get("Raises", [])):
        out.append("no Raises section naming SolasError (it raises one)")
    return out


def attribute_doc(module: str, name: str) -> str | None:
    """The docstring of a module attribute: the string right after its assignment."""
    body = hooks.module_tree(module).body
    for node, following in itertools.pairwise(body):
        targets = node.targets if isinstance(node, ast.Assign) else [getattr(node, "target", None)]
        documented = isinstance(following, ast.Expr) and isinstance(following.value, ast.Constant)
        if documented and name in [getattr(t, "id", None) for t in targets]:
            return str(following.value.value)
    return None


def class_members(cls) -> list[tuple[str, object]]:
    """(name, member) of the public methods and properties defined in a class's own body."""
    return [
        (name, member)
        for name, member in vars(cls).items()
        if not name.startswith("_")
        and (inspect.isfunction(member) or isinstance(member, (classmethod, staticmethod, property)))
    ]


def check(path: str, module: str, name: str) -> dict[str, list[str]]:
    """Public path of the object and of each of its members → what its docstring lacks."""
    obj = getattr(importlib.import_module(module), name)
    if not (inspect.isclass(obj) or inspect.isfunction(obj)):
        return {path: [] if attribute_doc(module, name) else ["no docstring (a string right after its assignment)"]}
    if inspect.isfunction(obj):
        node = function_node(obj)
        return {
            path: problems(obj.__doc__, parameters(obj), returns_value(node), yields(node), raises_solas_error(node))
        }
    inits = [function_node(vars(obj)[n]) for n in ("__init__", "__post_init__") if inspect.isfunction(vars(obj).get(n))]
    found = {path: problems(obj.__doc__, parameters(obj), raises=any(raises_solas_error(n) for n in inits if n))}
    for member_name, member in class_members(obj):
        where = f"{path}.{member_name}"
        if isinstance(member, property):
            found[where] = [] if (member.__doc__ or "").strip() else ["no docstring"]
            continue
        function = member.__func__ if isinstance(member, (classmethod, staticmethod)) else member
        node = function_node(function)
        found[where] = problems(
            function.__doc__, parameters(function), returns_value(node), yields(node), raises_solas_error(node)
        )
    return found


def public():
    """(public path, defining module, name) of each public name, each definition once."""
    seen, out = set(), []
    for package, names in hooks.public_api().items():
        for name, module in names:
            if f"{module}.{name}" not in seen:
                seen.add(f"{module}.{name}")
                out.append((f"{package}.{name}", module, name))
    return out


def test_every_package_declares_its_public_names():
    missing = [package for package in hooks.packages() if hooks.declared_all(package) is None]
    assert not missing, f"packages without __all__: {missing}"
    assert len(public()) >= 30


@pytest.mark.parametrize("path, module, name", public(), ids=[p for p, _, _ in public()])
def test_public_docstrings_are_numpydoc(path, module, name):
    lacking = {where: what for where, what in check(path, module, name).items() if what}
    assert not lacking, "\n".join(f"{where}: {'; '.join(what)}" for where, what in lacking.items())


@pytest.mark.parametrize(
    "doc, params, returns, raises, expected",
    [
        (
            "Sum.\n\nParameters\n----------\na : int\n    A.\nb\n    B.\n\nReturns\n-------\nint\n",
            ["a", "b"],
            True,
            False,
            [],
        ),
        (
            "Sum of a and b.",
            ["a", "b"],
            True,
            False,
            ["no Parameters section (takes a, b)", "no Returns section (it returns a value)"],
        ),
        (
            "Sum.\n\nParameters\n----------\na, c : int\n    A.\n",
            ["a", "b"],
            False,
            False,
            ["Parameters does not name b", "Parameters names c, which it does not take"],
        ),
        (
            "Go.\n\nArgs:\n    a: A.\n",
            [],
            False,
            False,
            ["a header of another style (numpydoc: the name, then a line of dashes)"],
        ),
        (
            "Go.\n\nRaises\n------\nValueError\n    Bad.\n",
            [],
            False,
            True,
            ["no Raises section naming SolasError (it raises one)"],
        ),
        ("Go.\n\nReturns\n----\nint\n", [], True, False, ["Returns: its underline is not as long as it"]),
        ("Go.\n\nParameters\n----------\n**options\n    Any.\n", ["options"], False, False, []),
        ("", [], False, False, ["no docstring"]),
    ],
)
def test_the_check_finds_what_a_docstring_lacks(doc, params, returns, raises, expected):
    assert problems(doc, params, returns=returns, raises=raises) == expected


def test_the_check_sees_returns_and_raises_in_the_function_itself():
    source = (
        "def f(x):\n    def inner():\n        return 1\n    if x:\n        raise SolasError('x')\n    return None\n"
    )
    node = ast.parse(source).body[0]
    assert not returns_value(node) and raises_solas_error(node) and not yields(node)
