"""Run benchmarks and record their output in benchmarks/results/<name>.md (the documentation's benchmark
and validation pages include those files, so no number there is pasted by hand).

    python benchmarks/run_all.py                   # the quick set (a few minutes on 2 cores): `make bench`
    python benchmarks/run_all.py bench_convolution # one benchmark, by name
    python benchmarks/run_all.py --all             # every bench_*.py (over an hour on 2 cores): `make bench-all`
"""
from __future__ import annotations

import argparse
import datetime
import os
import platform
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
# name → arguments of the quick run; the quick set is what `make bench` runs
QUICK = {"bench_psf_grid": ["--repeats", "3", "--skip-grid"], "bench_esfr": []}


def run(name: str, arguments: list[str]) -> None:
    """Run one benchmark, echo its output, and write it with the command and machine to results/NAME.md
    (under a temporary name first: a failed run leaves the previous results as they were)."""
    command = [sys.executable, str(HERE / f"{name}.py"), *arguments]
    print(f"\n## {name}\n", flush=True)
    done = subprocess.run(command, check=True, stdout=subprocess.PIPE, text=True)
    print(done.stdout, flush=True)
    shown = " ".join(["python", f"benchmarks/{name}.py", *arguments])
    header = (f"<!-- written by benchmarks/run_all.py; do not edit -->\n"
              f"`{shown}`, {datetime.date.today().isoformat()}, {platform.machine()} with {os.cpu_count()} cores:\n\n")
    RESULTS.mkdir(exist_ok=True)
    tmp = RESULTS / f".{name}.md.tmp"
    tmp.write_text(header + done.stdout.strip() + "\n", encoding="utf-8")
    tmp.replace(RESULTS / f"{name}.md")


def main(argv: list[str] | None = None) -> int:
    every = sorted(p.stem for p in HERE.glob("bench_*.py"))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", help=f"benchmarks to run (default: the quick set {', '.join(QUICK)})")
    ap.add_argument("--all", action="store_true", help="run every benchmark with its default arguments")
    args = ap.parse_args(argv)
    unknown = sorted(set(args.names) - set(every))
    if unknown:
        ap.error(f"unknown benchmark {', '.join(unknown)}; there are: {', '.join(every)}")
    chosen = {n: [] for n in every} if args.all else {n: QUICK.get(n, []) for n in args.names} or QUICK
    for name, arguments in chosen.items():
        run(name, arguments)
    return 0


if __name__ == "__main__":
    sys.exit(main())
