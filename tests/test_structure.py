"""The code's shape: no function or method in solas_mi/ or plugins/ over MAX_FUNCTION_LINES lines unless
a comment says why. The marker is a comment starting `# long:` followed by the reason, written in the
function's body or on the lines directly above it (above its decorators), e.g.

    # long: one table of 40 rows read top to bottom; split, it would be read in two places
    def table(...):

Nor one taking more than MAX_PARAMETERS parameters (a method's self or cls not counted; *args and
**kwargs one each) unless a comment directly above it says why, `# many parameters:` and the reason;
options that travel together are one option spec (`options.OptionSpec`: GridSpec, RenderSpec,
DegradeSpec) instead.
"""

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MAX_FUNCTION_LINES = 60
MARKER = re.compile(r"#\s*long:\s*\S")  # "# long: <reason>", the reason not empty
MAX_PARAMETERS = 10
MANY_MARKER = re.compile(r"#\s*many parameters:\s*\S")  # "# many parameters: <reason>", the reason not empty


def definitions(source: str) -> list[tuple[str, ast.FunctionDef | ast.AsyncFunctionDef]]:
    """(qualified name, node) of each function and method in `source`, nested ones included."""
    found = []

    def visit(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                found.append((f"{prefix}{child.name}", child))
                visit(child, f"{prefix}{child.name}.")
            elif isinstance(child, ast.ClassDef):
                visit(child, f"{prefix}{child.name}.")
            else:
                visit(child, prefix)

    visit(ast.parse(source), "")
    return found


def _top(node) -> int:
    """The first line of a definition: its first decorator's, else its `def`'s."""
    return min([d.lineno for d in node.decorator_list] + [node.lineno])


def functions(source: str):
    """(qualified name, first line, last line, lines, top line) of each function and method in `source`:
    from its `def` (decorators not counted) to its last line, docstring, comments and blank lines included."""
    return [
        (name, node.lineno, node.end_lineno, node.end_lineno - node.lineno + 1, _top(node))
        for name, node in definitions(source)
    ]


def says_why(lines: list[str], first: int, last: int, top: int) -> bool:
    """Whether a `# long:` comment stands in lines first..last (1-based: the body) or in the block of
    comment lines directly above line `top` (the def or its first decorator)."""
    return any(MARKER.search(line) for line in lines[first - 1 : last]) or says_above(lines, top, MARKER)


def says_above(lines: list[str], top: int, marker: re.Pattern) -> bool:
    """Whether `marker` stands in the block of comment lines directly above line `top` (1-based)."""
    k = top - 2
    while k >= 0 and lines[k].strip().startswith("#"):
        if marker.search(lines[k]):
            return True
        k -= 1
    return False


def parameter_count(node) -> int:
    """The parameters of a function: positional-only, positional, *args, keyword-only, **kwargs; a first
    one named self or cls (a method's) not counted."""
    a = node.args
    names = [p.arg for p in a.posonlyargs + a.args]
    count = len(names) + len(a.kwonlyargs) + (a.vararg is not None) + (a.kwarg is not None)
    return count - (bool(names) and names[0] in ("self", "cls"))


def crowded_functions(source: str, limit: int = MAX_PARAMETERS) -> dict[str, int]:
    """Name → parameters of each function of `source` taking more than `limit` without a
    `# many parameters:` reason directly above it."""
    lines = source.splitlines()
    return {
        name: n
        for name, node in definitions(source)
        if (n := parameter_count(node)) > limit and not says_above(lines, _top(node), MANY_MARKER)
    }


def long_functions(source: str, limit: int = MAX_FUNCTION_LINES) -> dict[str, int]:
    """Name → lines of each function of `source` over `limit` lines without a `# long:` reason."""
    lines = source.splitlines()
    return {
        name: n
        for name, first, last, n, top in functions(source)
        if n > limit and not says_why(lines, first, last, top)
    }


def sources():
    for base in (ROOT / "solas_mi", ROOT / "plugins"):
        yield from sorted(base.rglob("*.py"))


def test_no_function_over_the_limit_without_a_reason():
    long = {
        f"{path.relative_to(ROOT)}:{name}": n
        for path in sources()
        for name, n in long_functions(path.read_text()).items()
    }
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines without a '# long: <reason>' comment: " + ", ".join(
        f"{k} ({n})" for k, n in sorted(long.items(), key=lambda kv: -kv[1])
    )


def _body(n: int) -> str:
    return "".join(f"    x{i} = {i}\n" for i in range(n))


@pytest.mark.parametrize(
    "code, expected",
    [
        ("def f():\n" + _body(59), {}),  # 60 lines with the def: at the limit
        ("def f():\n" + _body(60), {"f": 61}),
        ("class A:\n    def m(self):\n" + _body(60).replace("    ", "        "), {"A.m": 61}),
        ("def f():\n    def g():\n" + _body(60).replace("    ", "        "), {"f": 62, "f.g": 61}),
        ("def f():\n    # long: one table read top to bottom\n" + _body(60), {}),
        ("# long: one table read top to bottom\n@decorator\ndef f():\n" + _body(60), {}),
        ("# long: reason\n\ndef f():\n" + _body(60), {"f": 61}),  # a blank line between: not directly above
        ("def f():\n    # long:\n" + _body(60), {"f": 62}),  # no reason given
        ("def f():\n    # this is long: no marker\n" + _body(60), {"f": 62}),
    ],
)
def test_the_limit_and_its_marker(code, expected):
    assert long_functions(code) == expected


def test_no_function_takes_over_the_limit_of_parameters_without_a_reason():
    crowded = {
        f"{path.relative_to(ROOT)}:{name}": n
        for path in sources()
        for name, n in crowded_functions(path.read_text()).items()
    }
    assert not crowded, (
        f"functions of more than {MAX_PARAMETERS} parameters without a '# many parameters: <reason>' "
        "comment above them (options that travel together are one option spec): "
        + ", ".join(f"{k} ({n})" for k, n in sorted(crowded.items(), key=lambda kv: -kv[1]))
    )


def _signature(n: int, first: str = "") -> str:
    return ", ".join([first] * bool(first) + [f"p{i}" for i in range(n)])


@pytest.mark.parametrize(
    "code, expected",
    [
        (f"def f({_signature(10)}):\n    pass\n", {}),  # at the limit
        (f"def f({_signature(11)}):\n    pass\n", {"f": 11}),
        (f"class A:\n    def m({_signature(10, 'self')}):\n        pass\n", {}),  # self is not counted
        (f"class A:\n    @classmethod\n    def m({_signature(11, 'cls')}):\n        pass\n", {"A.m": 11}),
        ("def f(a, /, b, *args, c, d, e, f, g, h, i, **kwargs):\n    pass\n", {"f": 11}),  # every kind counted
        (f"def f():\n    def g({_signature(11)}):\n        pass\n", {"f.g": 11}),
        (f"# many parameters: the kernel's scalars, each opaque\ndef f({_signature(11)}):\n    pass\n", {}),
        (f"# many parameters: reason\n# and more of it\n@decorator\ndef f({_signature(11)}):\n    pass\n", {}),
        (f"# many parameters: reason\n\ndef f({_signature(11)}):\n    pass\n", {"f": 11}),  # not directly above
        (f"# many parameters:\ndef f({_signature(11)}):\n    pass\n", {"f": 11}),  # no reason given
        (f"def f({_signature(11)}):\n    # many parameters: in the body\n    pass\n", {"f": 11}),  # above, not inside
        (f"# long: a reason of the other rule\ndef f({_signature(11)}):\n    pass\n", {"f": 11}),
    ],
)
def test_the_parameter_limit_and_its_marker(code, expected):
    assert crowded_functions(code) == expected
