"""Run benchmarks and validation commands and record their output in benchmarks/results/<name>.md (the
documentation's benchmark and validation pages include those files, so no number there is pasted by
hand; `docs/tools/check_pages.py` checks that every table on those pages is such an include).

    python benchmarks/run_all.py                   # the quick set (a few minutes on 2 cores): `make bench`
    python benchmarks/run_all.py bench_convolution # one benchmark, by name
    python benchmarks/run_all.py --all             # every bench_*.py (over an hour on 2 cores): `make bench-all`,
                                                   # but those of SIDE, which need another tool's environment
"""
from __future__ import annotations

import argparse
import datetime
import os
import platform
import re
import shlex
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
ANSI = re.compile(r"\x1b\[[0-9;]*m")  # terminal colours (Mitsuba's log) kept out of the Markdown
# Mitsuba's log lines ("2026-11-26 00:16:11 WARN  [HDRFilm] ..."), which it writes to stdout: echoed, not recorded
LOG_LINE = re.compile(r"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d +(TRACE|DEBUG|INFO|WARN|ERROR)\b.*")
# Validation runs of the command line whose tables the validation pages include: name → the
# solas-mi arguments (run as `python -m solas_mi`, from the repository root).
COMMANDS = {
    "check_stability_solas-doublet": ["check-stability", "solas-doublet"],
    "check_stability_cooke-triplet": ["check-stability", "cooke-triplet"],
    "crossval_headline": ["crossval", "solas-doublet", "scenes/images/rocket.png", "-o", "out/bench/crossval",
                          "--spp", "768"],
}
# benchmarks that need another tool installed beside this one: run by name, never by --all
SIDE = {"bench_optiland": "optiland in a side environment (.optiland-venv or $OPTILAND_PYTHON)"}
# name → arguments of the quick run; the quick set is what `make bench` runs
QUICK = {"bench_psf_grid": ["--repeats", "3"], "bench_esfr": [], "bench_anchors": [], "bench_sensor_isp": [],
         "check_stability_solas-doublet": COMMANDS["check_stability_solas-doublet"],
         "check_stability_cooke-triplet": COMMANDS["check_stability_cooke-triplet"]}


def recorded(stdout: str) -> str:
    """What a results file holds of a run's stdout: its tables and lines of text as Markdown, without the
    log lines of the libraries it ran (`LOG_LINE`), terminal colours or this checkout's paths; each line of
    text a paragraph of its own and each table a block (Markdown would run consecutive lines together)."""
    kept = [line.rstrip() for line in ANSI.sub("", stdout).replace(f"{HERE.parent}/", "").splitlines()
            if not LOG_LINE.fullmatch(line.strip())]
    out: list[str] = []
    for line in kept:
        if line and out and out[-1] and not (_is_row(line) and _is_row(out[-1])):
            out.append("")  # a line of text after another line, or a table's edge
        if line or (out and out[-1]):
            out.append(line)
    return "\n".join(out).strip() + "\n"


def _is_row(line: str) -> bool:
    return line.lstrip().startswith("|")


def run(name: str, arguments: list[str]) -> None:
    """Run one benchmark or validation command, echo its output, and write it with the command and
    machine to results/NAME.md (under a temporary name first: a failed run leaves the previous results
    as they were)."""
    if name in COMMANDS:
        command, shown = [sys.executable, "-m", "solas_mi", *arguments], " ".join(["solas-mi", *arguments])
    else:
        command = [sys.executable, str(HERE / f"{name}.py"), *arguments]
        shown = " ".join(["python", f"benchmarks/{name}.py", *arguments])
    print(f"\n## {name}\n", flush=True)
    load = os.getloadavg()[0]  # timings on a shared machine depend on the other jobs: recorded beside them
    done = subprocess.run(command, check=True, stdout=subprocess.PIPE, text=True, cwd=HERE.parent)
    print(done.stdout, flush=True)
    header = (f"<!-- written by benchmarks/run_all.py; do not edit -->\n"
              f"`{shown}`, {datetime.date.today().isoformat()}, {platform.machine()} with {os.cpu_count()} cores, "
              f"load average {load:.1f} before the run:\n\n")
    RESULTS.mkdir(exist_ok=True)
    tmp = RESULTS / f".{name}.md.tmp"
    tmp.write_text(header + recorded(done.stdout), encoding="utf-8")
    tmp.replace(RESULTS / f"{name}.md")


def main(argv: list[str] | None = None) -> int:
    every = sorted(p.stem for p in HERE.glob("bench_*.py")) + list(COMMANDS)
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", help=f"benchmarks to run (default: the quick set {', '.join(QUICK)})")
    ap.add_argument("--all", action="store_true", help="run every benchmark with its default arguments")
    ap.add_argument("--arguments", help="the arguments of the one benchmark named, in place of its quick "
                    "set's or default ones (e.g. --arguments='--repeats 2')")
    args = ap.parse_args(argv)
    if args.arguments is not None and len(args.names) != 1:
        ap.error("--arguments needs exactly one benchmark named")
    unknown = sorted(set(args.names) - set(every))
    if unknown:
        ap.error(f"unknown benchmark {', '.join(unknown)}; there are: {', '.join(every)}")
    defaults = {**{n: [] for n in every}, **COMMANDS}
    every_one = {n: a for n, a in defaults.items() if n not in SIDE}
    chosen = every_one if args.all else {n: QUICK.get(n, defaults[n]) for n in args.names} or QUICK
    if args.arguments is not None:
        chosen = {args.names[0]: shlex.split(args.arguments)}
    for name, arguments in chosen.items():
        run(name, arguments)
    return 0


if __name__ == "__main__":
    sys.exit(main())
