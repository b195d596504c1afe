"""Every two-reflection ghost of a lens at one field (`solas_mi.psf.ghosts`: the ghost table, without the
HDR PSF's direct image), three wavelengths, 128 × 128 rays per path.

Run: .venv/bin/python benchmarks/bench_ghosts.py [--repeats 5]
Per shipped lens: its reflecting surfaces, the paths C(N, 2), the wall-clock median and min–max of
`ghosts(lens, (0, 0.7 × its half field))` after one warm-up call, and every ghost's energy together
relative to the direct image. The issue's target: the double Gauss in at most 2 s on 2 cores.
"""

from __future__ import annotations

import argparse
import time
from statistics import median

from solas_mi import Lens
from solas_mi.optics.ghost_paths import reflecting
from solas_mi.psf import ghosts

LENSES = ("solas-doublet", "cooke-triplet", "double-gauss-50mm", "wide-angle-22mm")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    print("| lens | reflecting surfaces | paths | wall median (s) | wall min–max (s) | all ghosts / direct |")
    print("|---|---|---|---|---|---|")
    for name in LENSES:
        lens = Lens.load(name)
        field = (0.0, 0.7 * lens.field_deg)
        report = ghosts(lens, field)  # warm-up
        times = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            report = ghosts(lens, field)
            times.append(time.perf_counter() - start)
        n = len(reflecting(lens))
        print(
            f"| {name} | {n} | {len(report.ghosts)} | {median(times):.2f} | {min(times):.2f}–{max(times):.2f} | "
            f"{report.total:.3e} |"
        )


if __name__ == "__main__":
    main()
