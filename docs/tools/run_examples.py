"""Run the examples of the README and the user guide, as a reader would, and check their stated output.

Every fenced ```sh and ```python block of the given Markdown files (folders: their *.md) runs, in the
order of the page, in a fresh temporary folder per page that holds a link to the repository's scenes/
(so `scenes/images/rocket.png` works as it does from the repository root), with this environment's
`solas-mi` first on PATH. Other fences (xml, toml, text) are not run. Checks and marks, as HTML
comments that the site does not show:

- `<!-- example: expect "TEXT" -->` after a block: its output must contain TEXT;
- in Python, `EXPRESSION  # → VALUE` on a line: the expression must give VALUE (to the printed digits
  for a number, else its repr or str);
- `<!-- example: slow -->` before a block: left out by --quick;
- `<!-- example: skip REASON -->` before a block: never run here; the reason is required (say why:
  `make test` runs itself, an hour-long benchmark, inputs only the reader has) and listed in the summary.

A block fails when it exits non-zero, misses a stated output, or prints a warning (": warning:"). No
runnable block is left out silently: a fence of another language (text, none) whose lines read as
commands (`solas-mi …`, `make …`, `python …`, `from solas_mi …`) fails unless it is marked skip
with its reason — write it as ```sh or ```python to have it run.

The site's API reference is generated from the docstrings (`hooks.py`), so with the docs folder the
docstrings' Examples (numpydoc, `>>>` lines and their output) run too: each module's with `doctest`, in
a fresh folder of its own like a page's; a module fails when an example's output differs from the
docstring's or an example raises.

    python docs/tools/run_examples.py README.md docs [--quick] [--keep]
"""

from __future__ import annotations

import argparse
import ast
import os
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DOCS = REPO / "docs"
FENCE = re.compile(r"^```(\w+)[^\n]*\n(.*?)^```\s*$", re.M | re.S)
MARK = re.compile(r"<!--\s*example:\s*(expect|slow|skip)\s*(.*?)\s*-->")
RUN = {"sh": "sh", "bash": "sh", "python": "python"}
# a line of a non-run fence that reads as a command or Python a reader would run
COMMAND_LINE = re.compile(r"^\s*(\$ |solas-mi |make |python3? |\.venv/|dask |from solas_mi|import solas_mi)", re.M)
FENCE_ANY = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```\s*$", re.M | re.S)
MIN_REASON = 15  # characters: a skip says why
EXPECT = "# → "
CHECK = """
def __expect(value, stated, where):
    text = str(value)
    if text == stated or repr(value) == stated:
        return
    try:
        number, digits = float(stated), len(stated.partition(".")[2]) if "." in stated else 0
        if abs(float(value) - number) <= 0.5 * 10 ** -digits * (1 + 1e-9):
            return
    except (TypeError, ValueError):
        pass
    raise SystemExit(f"{where}: gave {text}, the page states {stated}")
"""


@dataclass
class Example:
    page: Path
    line: int
    language: str
    code: str
    expect: list[str] = field(default_factory=list)
    slow: bool = False
    skip: str = ""


def examples(page: Path) -> list[Example]:
    """The runnable blocks of `page` with their marks."""
    text = page.read_text(encoding="utf-8")
    found: list[Example] = []
    pending: dict = {}
    spans = sorted(
        [(m.start(), "fence", m) for m in FENCE_ANY.finditer(text)]
        + [(m.start(), "mark", m) for m in MARK.finditer(text)],
        key=lambda s: s[0],
    )
    for start, kind, m in spans:
        if kind == "mark":
            what, arg = m.group(1), m.group(2)
            if what == "expect":
                if not found:
                    raise SystemExit(f"{page}: an expect mark before any example")
                found[-1].expect.append(arg.strip('"'))
            else:
                if what == "skip" and len(arg) < MIN_REASON:
                    raise SystemExit(f"{page}:{text.count(chr(10), 0, start) + 1}: a skip mark needs its reason")
                pending[what] = arg or True
        elif m.group(1) in RUN or COMMAND_LINE.search(m.group(2)):
            language = RUN.get(m.group(1), "text")
            found.append(
                Example(
                    page,
                    text.count("\n", 0, start) + 1,
                    language,
                    m.group(2),
                    slow=bool(pending.get("slow")),
                    skip=str(pending.get("skip") or ""),
                )
            )
            pending = {}
        else:
            pending = {}
    return found


def python_source(example: Example) -> str:
    """The block with each `EXPR  # → VALUE` line turned into a check."""
    lines = [CHECK]
    for i, line in enumerate(example.code.splitlines()):
        code, sep, stated = line.partition(EXPECT)
        if sep:
            ast.parse(code.strip(), mode="eval")  # a statement stated to give a value is a mistake of the page
            indent = code[: len(code) - len(code.lstrip())]
            where = f"{example.page.name}:{example.line + 1 + i}"
            line = f"{indent}__expect({code.strip()}, {stated.strip()!r}, {where!r})"
        lines.append(line)
    return "\n".join(lines) + "\n"


def run(example: Example, folder: Path, env: dict) -> tuple[bool, str, float]:
    start = time.perf_counter()
    if example.language == "python":
        script = folder / f"_example_{example.line}.py"
        script.write_text(python_source(example), encoding="utf-8")
        command = [sys.executable, script.name]
    else:
        command = ["bash", "-e", "-o", "pipefail", "-c", example.code]
    done = subprocess.run(command, cwd=folder, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    output = done.stdout
    missing = [e for e in example.expect if e not in output]
    warned = ": warning:" in output  # a recipe on a page must run without warnings
    ok = done.returncode == 0 and not missing and not warned
    if missing:
        output += f"\n(the page states output containing {missing})"
    if warned:
        output += "\n(a recipe on a page must run without warnings)"
    return ok, output, time.perf_counter() - start


def environment() -> dict:
    """The examples' environment: this Python's `solas-mi` first on PATH, matplotlib without a display."""
    return dict(
        os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}", MPLBACKEND="Agg"
    )


def fresh_folder(stem: str) -> Path:
    """A new temporary folder holding a link to the repository's scenes/, as a reader's checkout has it."""
    folder = Path(tempfile.mkdtemp(prefix=f"solas-mi-docs-{stem}-"))
    (folder / "scenes").symlink_to(REPO / "scenes")
    return folder


def run_page(page: Path, quick: bool, keep: bool) -> int:
    """Run one page's examples in order in a fresh folder; the number that failed."""
    env, folder = environment(), fresh_folder(page.stem)
    failed = 0
    for ex in examples(page):
        where = f"{os.path.relpath(page, REPO)}:{ex.line}"
        if ex.skip or (quick and ex.slow):
            print(f"  skip {where} ({ex.skip or 'slow'})")
            continue
        if ex.language == "text":
            failed += 1
            print(
                f"  FAIL {where}: commands in a fence that is not run; write it as ```sh or ```python, or mark it "
                "<!-- example: skip REASON -->"
            )
            continue
        ok, output, seconds = run(ex, folder, env)
        print(f"  {'ok  ' if ok else 'FAIL'} {where} ({ex.language}, {seconds:.1f} s)", flush=True)
        if not ok:
            failed += 1
            print("    " + output.strip().replace("\n", "\n    "))
    if not keep:
        subprocess.run(["rm", "-rf", str(folder)], check=False)
    return failed


DOCTEST = (
    "import doctest, importlib, sys; result = doctest.testmod(importlib.import_module({name!r}), "
    "optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE); "
    "print(f'{{result.attempted}} examples, {{result.failed}} failed'); sys.exit(1 if result.failed else 0)"
)


def docstring_modules() -> list[str]:
    """The modules of the API reference (`hooks.api_modules`) whose docstrings hold examples (`>>>`)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from hooks import api_modules, module_file

    return [name for _, name in api_modules() if ">>> " in module_file(name).read_text(encoding="utf-8")]


def run_docstrings(keep: bool) -> int:
    """Run the docstrings' examples of each module that has some, each module in a fresh folder; the number
    of modules that failed."""
    failed = 0
    for name in docstring_modules():
        folder, start = fresh_folder(name.rpartition(".")[2]), time.perf_counter()
        done = subprocess.run(
            [sys.executable, "-c", DOCTEST.format(name=name)],
            cwd=folder,
            env=environment(),
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        ok = done.returncode == 0 and ": warning:" not in done.stdout
        summary = done.stdout.strip().splitlines()[-1] if done.stdout.strip() else ""
        print(
            f"  {'ok  ' if ok else 'FAIL'} {name} (docstrings: {summary}, {time.perf_counter() - start:.1f} s)",
            flush=True,
        )
        if not ok:
            failed += 1
            print("    " + done.stdout.strip().replace("\n", "\n    "))
        if not keep:
            subprocess.run(["rm", "-rf", str(folder)], check=False)
    return failed


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("paths", nargs="+", type=Path, help="Markdown files or folders of them")
    ap.add_argument("--quick", action="store_true", help="leave out the blocks marked slow")
    ap.add_argument("--keep", action="store_true", help="keep each page's folder (its path is printed)")
    args = ap.parse_args(argv)
    pages = [p for path in args.paths for p in (sorted(path.rglob("*.md")) if path.is_dir() else [path])]
    start, failed = time.perf_counter(), 0
    for page in pages:
        print(f"{page}:", flush=True)
        failed += run_page(page.resolve(), args.quick, args.keep)
    if DOCS in [path.resolve() for path in args.paths]:
        print("docs/reference/api.md (generated from the docstrings):", flush=True)
        failed += run_docstrings(args.keep)
    print(f"examples: {failed} failed, {time.perf_counter() - start:.0f} s")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
