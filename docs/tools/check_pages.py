"""Check that the numbers on the benchmark and validation pages come from the runs' own output files.

Every table on those pages must be an include of a results file that `benchmarks/run_all.py` wrote
(`--8<-- "benchmarks/results/NAME.md"`, a file whose first line is run_all's header), never a table
typed into the page; and each results file must be as run_all's recorder writes a run's output
(`run_all.recorded`: no library's raw log, no lines of text Markdown would run together). A table that
no run here can make (one that needs another tool installed beside this one) is allowed only under
`<!-- table: recorded REASON -->`, and is listed. Exit 1 on any problem.

    python docs/tools/check_pages.py [PAGES ...]     # default: docs/benchmarks.md docs/validation
"""

from __future__ import annotations

import importlib.util
import re
import sys
from functools import cache
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DEFAULT_PAGES = ("docs/benchmarks.md", "docs/validation")
# run_all.py writes every benchmark's file; gpu_cuda.py (run by hand where a GPU is) writes its own
HEADER = re.compile(r"<!-- written by benchmarks/(run_all|gpu_cuda)\.py; do not edit -->")
INCLUDE = re.compile(r'^--8<--\s+"([^"]+)"\s*$')
RECORDED = re.compile(r"^<!--\s*table:\s*recorded\s+(.*?)\s*-->$")
MIN_REASON = 15  # characters: a recorded table says why no run makes it
HEADER_LINES = 3  # of a results file: the marker, the command and machine, a blank line


@cache
def recorder():
    """benchmarks/run_all.py, whose `recorded` says what a results file holds of a run's output."""
    spec = importlib.util.spec_from_file_location("run_all", REPO / "benchmarks" / "run_all.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def unrecorded(text: str) -> bool:
    """Whether a results file's text holds more than, or other than, what the recorder keeps."""
    body = "".join(text.splitlines(keepends=True)[HEADER_LINES:])
    return recorder().recorded(body) != body


def check(page: Path) -> tuple[list[str], list[str], list[str]]:
    """(problems, included results files, recorded tables with their reasons) of one page."""
    problems, included, recorded = [], [], []
    name = page.relative_to(REPO) if page.is_relative_to(REPO) else page
    lines = page.read_text(encoding="utf-8").splitlines()
    fenced, previous = False, ""
    for number, line in enumerate(lines, start=1):
        where = f"{name}:{number}"
        if line.startswith("```"):
            fenced = not fenced
        elif (m := INCLUDE.match(line)) and not fenced:
            target = REPO / m.group(1)
            if not m.group(1).startswith("benchmarks/results/"):
                problems.append(f"{where}: includes {m.group(1)}, not a results file of benchmarks/results/")
            elif not target.is_file():
                problems.append(f"{where}: includes {m.group(1)}, which does not exist (run benchmarks/run_all.py)")
            elif not HEADER.fullmatch(target.read_text(encoding="utf-8").partition("\n")[0]):
                problems.append(f"{where}: {m.group(1)} was not written by benchmarks/run_all.py")
            elif unrecorded(target.read_text(encoding="utf-8")):
                problems.append(
                    f"{where}: {m.group(1)} holds what the recorder leaves out (a raw log, lines run "
                    "together): record it again with benchmarks/run_all.py"
                )
            else:
                included.append(m.group(1))
        elif (
            line.lstrip().startswith("|")
            and not fenced
            and (number == 1 or not lines[number - 2].lstrip().startswith("|"))
        ):
            reason = RECORDED.match(previous)
            if reason is None:
                problems.append(
                    f"{where}: a table typed into the page; include the results file of the run "
                    "that prints it (benchmarks/run_all.py)"
                )
            elif len(reason.group(1)) < MIN_REASON:
                problems.append(f"{where}: a recorded table needs its reason")
            else:
                recorded.append(f"{where}: {reason.group(1)}")
        if line.strip():
            previous = line.strip()
    return problems, included, recorded


def pages(paths: list[str]) -> list[Path]:
    found = []
    for text in paths:
        path = REPO / text
        found.extend(sorted(path.rglob("*.md")) if path.is_dir() else [path])
    return found


def main(argv: list[str] | None = None) -> int:
    paths = (sys.argv[1:] if argv is None else argv) or list(DEFAULT_PAGES)
    problems, included, recorded = [], [], []
    for page in pages(paths):
        p, i, r = check(page)
        problems += p
        included += i
        recorded += r
    for line in recorded:
        print(f"  recorded table (not from a results file): {line}")
    for line in problems:
        print(f"  FAIL {line}")
    print(
        f"tables: {len(included)} included from benchmarks/results/, {len(recorded)} recorded, {len(problems)} problems"
    )
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
