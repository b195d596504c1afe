"""The code's shape: no function or method in solas_mi/ or plugins/ over MAX_FUNCTION_LINES lines unless
a comment says why. The marker is a comment starting `# long:` followed by the reason, written in the
function's body or on the lines directly above it (above its decorators), e.g.

    # long: one table of 40 rows read top to bottom; split, it would be read in two places
    def table(...):
"""
import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MAX_FUNCTION_LINES = 60
MARKER = re.compile(r"#\s*long:\s*\S")  # "# long: <reason>", the reason not empty


def functions(source: str):
    """(qualified name, first line, last line, lines) of each function and method in `source`: from
    its `def` (decorators not counted) to its last line, docstring, comments and blank lines included."""
    found = []

    def visit(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = f"{prefix}{child.name}"
                found.append((name, child.lineno, child.end_lineno, child.end_lineno - child.lineno + 1,
                              min([d.lineno for d in child.decorator_list] + [child.lineno])))
                visit(child, name + ".")
            elif isinstance(child, ast.ClassDef):
                visit(child, f"{prefix}{child.name}.")
            else:
                visit(child, prefix)

    visit(ast.parse(source), "")
    return found


def says_why(lines: list[str], first: int, last: int, top: int) -> bool:
    """Whether a `# long:` comment stands in lines first..last (1-based: the body) or in the block of
    comment lines directly above line `top` (the def or its first decorator)."""
    if any(MARKER.search(line) for line in lines[first - 1:last]):
        return True
    k = top - 2
    while k >= 0 and lines[k].strip().startswith("#"):
        if MARKER.search(lines[k]):
            return True
        k -= 1
    return False


def long_functions(source: str, limit: int = MAX_FUNCTION_LINES) -> dict[str, int]:
    """Name → lines of each function of `source` over `limit` lines without a `# long:` reason."""
    lines = source.splitlines()
    return {name: n for name, first, last, n, top in functions(source)
            if n > limit and not says_why(lines, first, last, top)}


def sources():
    for base in (ROOT / "solas_mi", ROOT / "plugins"):
        yield from sorted(base.rglob("*.py"))


def test_no_function_over_the_limit_without_a_reason():
    long = {f"{path.relative_to(ROOT)}:{name}": n for path in sources()
            for name, n in long_functions(path.read_text()).items()}
    assert not long, (f"functions over {MAX_FUNCTION_LINES} lines without a '# long: <reason>' comment: "
                      + ", ".join(f"{k} ({n})" for k, n in sorted(long.items(), key=lambda kv: -kv[1])))


def _body(n: int) -> str:
    return "".join(f"    x{i} = {i}\n" for i in range(n))


@pytest.mark.parametrize("code, expected", [
    ("def f():\n" + _body(59), {}),  # 60 lines with the def: at the limit
    ("def f():\n" + _body(60), {"f": 61}),
    ("class A:\n    def m(self):\n" + _body(60).replace("    ", "        "), {"A.m": 61}),
    ("def f():\n    def g():\n" + _body(60).replace("    ", "        "), {"f": 62, "f.g": 61}),
    ("def f():\n    # long: one table read top to bottom\n" + _body(60), {}),
    ("# long: one table read top to bottom\n@decorator\ndef f():\n" + _body(60), {}),
    ("# long: reason\n\ndef f():\n" + _body(60), {"f": 61}),  # a blank line between: not directly above
    ("def f():\n    # long:\n" + _body(60), {"f": 62}),  # no reason given
    ("def f():\n    # this is long: no marker\n" + _body(60), {"f": 62}),
])
def test_the_limit_and_its_marker(code, expected):
    assert long_functions(code) == expected
