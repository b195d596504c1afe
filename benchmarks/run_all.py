"""Run benchmarks and validation commands and record their output in benchmarks/results/<name>.md (the
documentation's benchmark and validation pages include those files, so no number there is pasted by
hand; `docs/tools/check_pages.py` checks that every table on those pages is such an include).

    python benchmarks/run_all.py                   # the quick set (a few minutes on 2 cores): `make bench`
    python benchmarks/run_all.py bench_convolution # one benchmark, by name
    python benchmarks/run_all.py --all             # every bench_*.py (over an hour on 2 cores): `make bench-all`,
                                                   # but those of SIDE, which need another tool's environment

Each results file's header says how busy the machine was (`Machine`); a run on a busy machine (a load
above half the cores) is marked so and never sets a README headline. The figures a benchmark states
(`figures.py`) are compared with the recorded run's: a figure worse by more than 20 % between two runs on
an idle machine is a REGRESSION, said in the results file and on stderr, and the exit status is 1.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import re
import resource
import shlex
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from figures import IDLE_LOAD_PER_CORE, REGRESSION, figures, worse  # noqa: E402

RESULTS = HERE / "results"
ANSI = re.compile(r"\x1b\[[0-9;]*m")  # terminal colours (Mitsuba's log) kept out of the Markdown
# Mitsuba's log lines ("2026-11-26 00:16:11 WARN  [HDRFilm] ..."), which it writes to stdout: echoed, not recorded
LOG_LINE = re.compile(r"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d +(TRACE|DEBUG|INFO|WARN|ERROR)\b.*")
# Validation runs of the command line whose tables the validation pages include: name → the
# solas-mi arguments (run as `python -m solas_mi`, from the repository root).
COMMANDS = {
    "check_stability_solas-doublet": ["check-stability", "solas-doublet"],
    "check_stability_cooke-triplet": ["check-stability", "cooke-triplet"],
    "crossval_headline": [
        "crossval",
        "solas-doublet",
        "scenes/images/rocket.png",
        "-o",
        "out/bench/crossval",
        "--spp",
        "768",
    ],
}
# benchmarks that need another tool installed beside this one: run by name, never by --all
SIDE = {"bench_optiland": "optiland in a side environment (.optiland-venv or $OPTILAND_PYTHON)"}
# name → arguments of the quick run; the quick set is what `make bench` runs
QUICK = {
    "bench_psf_grid": ["--repeats", "5"],
    "bench_dataset": [],
    "bench_esfr": [],
    "bench_anchors": [],
    "bench_sensor_isp": [],
    "check_stability_solas-doublet": COMMANDS["check_stability_solas-doublet"],
    "check_stability_cooke-triplet": COMMANDS["check_stability_cooke-triplet"],
}


def recorded(stdout: str) -> str:
    """What a results file holds of a run's stdout: its tables and lines of text as Markdown, without the
    log lines of the libraries it ran (`LOG_LINE`), terminal colours or this checkout's paths; each line of
    text a paragraph of its own and each table a block (Markdown would run consecutive lines together)."""
    kept = [
        line.rstrip()
        for line in ANSI.sub("", stdout).replace(f"{HERE.parent}/", "").splitlines()
        if not LOG_LINE.fullmatch(line.strip())
    ]
    out: list[str] = []
    for line in kept:
        if line and out and out[-1] and not (_is_row(line) and _is_row(out[-1])):
            out.append("")  # a line of text after another line, or a table's edge
        if line or (out and out[-1]):
            out.append(line)
    return "\n".join(out).strip() + "\n"


def _is_row(line: str) -> bool:
    return line.lstrip().startswith("|")


def run(name: str, arguments: list[str]) -> list[str]:
    """Run one benchmark or validation command, echo its output, and write it with the command, the machine
    and how busy the machine was to results/NAME.md (under a temporary name first: a failed run leaves the
    previous results as they were), with its figures compared to the recorded run's (`compare`). A run on
    a busy machine is marked so, and updates no headline of the README (`headlines`). Returns the
    regressions found."""
    if name in COMMANDS:
        command, shown = [sys.executable, "-m", "solas_mi", *arguments], " ".join(["solas-mi", *arguments])
    else:
        command = [sys.executable, str(HERE / f"{name}.py"), *arguments]
        shown = " ".join(["python", f"benchmarks/{name}.py", *arguments])
    print(f"\n## {name}\n", flush=True)
    target = RESULTS / f"{name}.md"
    before = target.read_text(encoding="utf-8") if target.is_file() else ""
    with Machine() as machine:  # timings on a shared machine depend on the other jobs: recorded beside them
        done = subprocess.run(command, check=True, stdout=subprocess.PIPE, text=True, cwd=HERE.parent)
    print(done.stdout, flush=True)
    verdicts, regressions = compare(before, done.stdout, machine.idle)
    if machine.idle:
        verdicts += headlines(name, figures(done.stdout))
    print("\n".join(verdicts), flush=True)
    header = (
        f"<!-- written by benchmarks/run_all.py; do not edit -->\n"
        f"`{shown}`, {datetime.date.today().isoformat()}, {platform.machine()} with {os.cpu_count()} cores, "
        f"{machine.describe()}:\n\n"
    )
    RESULTS.mkdir(exist_ok=True)
    tmp = RESULTS / f".{name}.md.tmp"
    tmp.write_text(header + recorded(done.stdout + "\n" + "\n".join(verdicts)), encoding="utf-8")
    tmp.replace(target)
    return regressions


class Machine:
    """How busy the machine is around a run: the load average before it and the cores the other processes
    used during it (all processes' CPU time, /proc/stat, less the run's own children's)."""

    def __enter__(self):
        self.load, self.cores = os.getloadavg()[0], os.cpu_count() or 1
        self._start = (_busy_seconds(), _children_seconds(), time.perf_counter())
        return self

    def __exit__(self, *exc):
        busy, own, wall = (
            now - then for now, then in zip((_busy_seconds(), _children_seconds(), time.perf_counter()), self._start)
        )
        self.others = max(busy - own, 0.0) / max(wall, 1e-9)

    @property
    def idle(self) -> bool:
        return max(self.load, self.others) <= IDLE_LOAD_PER_CORE * self.cores

    def describe(self) -> str:
        text = f"load average {self.load:.1f} before the run, other processes using {self.others:.2f} cores during it"
        return text if self.idle else f"{text} ({BUSY}: these timings are no headline figures)"


BUSY = "a busy machine"  # what a results file's header says of a run on a machine not idle


def _busy_seconds() -> float:
    """CPU seconds all processes of the machine have used (user, nice, system, irq, softirq), /proc/stat."""
    try:
        with open("/proc/stat") as f:
            fields = [int(v) for v in f.readline().split()[1:]]
    except OSError:
        return 0.0
    return (fields[0] + fields[1] + fields[2] + fields[5] + fields[6]) / os.sysconf("SC_CLK_TCK")


def _children_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def compare(recorded_text: str, stdout: str, idle: bool) -> tuple[list[str], list[str]]:
    """Each figure of this run against the recorded run's (`figures`): lines saying by how much it changed,
    and the regressions (worse by more than REGRESSION, both runs on an idle machine)."""
    old, new = figures(recorded_text), figures(stdout)
    when = recorded_text.splitlines()[1].split(", ")[1] if recorded_text.count("\n") > 1 else "?"
    both_idle = idle and BUSY not in "".join(recorded_text.splitlines()[:2])
    lines, regressions = [], []
    for key in sorted(set(old) & set(new)):
        (a, unit), (b, _) = old[key], new[key]
        change = worse(a, b, unit)
        line = (
            f"against the run of {when}: {key} {a:.4g} → {b:.4g} {unit} "
            f"({100 * abs(change):.0f} % {'worse' if change > 0 else 'better'})"
        )
        if not both_idle:
            line += ", not judged (a run on a busy machine)"
        elif change > REGRESSION:
            line = f"REGRESSION {line}, beyond the {100 * REGRESSION:.0f} % allowed"
            regressions.append(line)
        lines.append(line)
    return lines, regressions


README = HERE.parent / "README.md"
HEADLINE = re.compile(r"<!-- headline (?P<bench>\w+) (?P<figure>[\w.-]+) -->(?P<value>.*?)<!-- /headline -->")


def headlines(name: str, found: dict[str, tuple[float, str]]) -> list[str]:
    """The README's headline figures of benchmark `name` (`<!-- headline NAME FIGURE -->value<!-- /headline
    -->`) set to this run's values (called for runs on an idle machine only); lines saying which."""
    if not README.is_file():
        return []
    text = README.read_text(encoding="utf-8")
    changed = []

    def value(m):
        if m["bench"] != name or m["figure"] not in found:
            return m.group(0)
        number, unit = found[m["figure"]]
        changed.append(f"README headline {m['figure']}: {number:.2g} {unit}")
        return f"<!-- headline {name} {m['figure']} -->{number:.2g} {unit}<!-- /headline -->"

    new = HEADLINE.sub(value, text)
    if new != text:
        README.write_text(new, encoding="utf-8")
    return changed


def main(argv: list[str] | None = None) -> int:
    every = sorted(p.stem for p in HERE.glob("bench_*.py")) + list(COMMANDS)
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", help=f"benchmarks to run (default: the quick set {', '.join(QUICK)})")
    ap.add_argument("--all", action="store_true", help="run every benchmark with its default arguments")
    ap.add_argument(
        "--arguments",
        help="the arguments of the one benchmark named, in place of its quick "
        "set's or default ones (e.g. --arguments='--repeats 2')",
    )
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
    regressions = [line for name, arguments in chosen.items() for line in run(name, arguments)]
    if regressions:
        print("\n" + "\n".join(regressions), file=sys.stderr)
    return 1 if regressions else 0


if __name__ == "__main__":
    sys.exit(main())
