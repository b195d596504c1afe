"""The 32×32×3 PSF grid of the doublet three ways: `psf_grid` in one process (kernels compiled), the
`solas-mi psf-grid` command end to end (a fresh process: imports, kernels, the grid, the EXR), and
`psf_grid` while another process keeps one of the cores busy. Runs alternate, so drifts in the
machine's speed fall on all three alike.

Run: .venv/bin/python benchmarks/bench_grid_end_to_end.py [--repeats 5]
Prints a Markdown table of medians and runs, and the two ratios the batch issue sets targets for
(command / in process ≤ 1.5, busy / idle ≤ 1.3).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from solas_mi import Lens
from solas_mi.psf import psf_grid

KW = dict(grid=(32, 32), wavelengths_nm=[656.0, 531.0, 486.0], pitch_um=0.5, size=160)
SPIN = "import time\nt = time.time()\nwhile time.time() - t < 600: pass\n"  # one busy core, pure Python


def in_process(lens: Lens) -> float:
    start = time.perf_counter()
    psf_grid(lens, **KW)
    return time.perf_counter() - start


def command(folder: Path) -> float:
    start = time.perf_counter()
    subprocess.run(
        [
            sys.executable,
            "-m",
            "solas_mi",
            "psf-grid",
            "solas-doublet",
            "--grid",
            "32x32",
            "--wavelengths-nm",
            "656,531,486",
            "--pitch-um",
            "0.5",
            "--size",
            "160",
            "-o",
            str(folder / "grid.exr"),
        ],
        check=True,
        capture_output=True,
    )
    return time.perf_counter() - start


def busy(lens: Lens) -> float:
    spinner = subprocess.Popen([sys.executable, "-c", SPIN])
    try:
        time.sleep(0.5)
        return in_process(lens)
    finally:
        spinner.kill()
        spinner.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    lens = Lens.load("solas-doublet")
    in_process(lens)  # compile the kernels once, as a long-running process would have
    runs = {"in process": [], "command end to end": [], "in process, one core busy": []}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.repeats):
            runs["in process"].append(in_process(lens))
            runs["command end to end"].append(command(Path(tmp)))
            runs["in process, one core busy"].append(busy(lens))
    print("| 32×32×3 grid | median (s) | runs (s) |\n|---|---|---|")
    for name, times in runs.items():
        print(f"| {name} | {statistics.median(times):.2f} | {', '.join(f'{t:.2f}' for t in times)} |")
    idle = statistics.median(runs["in process"])
    print(
        f"\ncommand / in process: {statistics.median(runs['command end to end']) / idle:.2f} (target ≤ 1.5); "
        f"busy / idle: {statistics.median(runs['in process, one core busy']) / idle:.2f} (target ≤ 1.3)"
    )


if __name__ == "__main__":
    main()
