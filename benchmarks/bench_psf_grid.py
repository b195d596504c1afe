"""PSF-grid speed and pupil-sampling error against run time for the SOLAS doublet.

Run: .venv/bin/python benchmarks/bench_psf_grid.py [--repeats 3] [--skip-grid]
Prints Markdown tables (the ones recorded in README.md).
"""
from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from solas_mi import Lens
from solas_mi.optics import pupil as P
from solas_mi.psf import psf, psf_grid
from solas_mi.psf.fraunhofer import fraunhofer
from solas_mi.psf.methods import compute
from solas_mi.psf.registry import DEFAULT_PUPIL_SAMPLES

FIELDS = np.array([[0.0, 0.0], [0.0, 2.0], [0.0, -2.0]] * 3)
WAVELENGTHS = np.repeat([486.0, 531.0, 656.0], 3)


def grid_seconds(lens: Lens, repeats: int) -> list[float]:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        psf_grid(lens, grid=(32, 32), wavelengths_nm=[656.0, 531.0, 486.0], pitch_um=0.5, size=160)
        times.append(time.perf_counter() - start)
    return times


def all_fields_seconds(lens: Lens) -> float:
    """The same 32×32×3 grid with every field traced (no use of the lens's mirror symmetry)."""
    fx = np.linspace(-2.0, 2.0, 32, endpoint=False) + 2.0 / 32
    fields = np.stack(np.meshgrid(fx, fx), axis=-1).reshape(-1, 2)
    start = time.perf_counter()
    for w in (656.0, 531.0, 486.0):
        for a in range(0, len(fields), 64):
            compute(lens, fields[a:a + 64], np.full(64, w), 0.5, 160, "fraunhofer",
                    pupil_samples=DEFAULT_PUPIL_SAMPLES)
    return time.perf_counter() - start


def sampling_sweep(lens: Lens, samples=(32, 64, 128, 256, 512), repeats: int = 3,
                   ) -> list[tuple[int, float, float, float]]:
    """(N, median seconds for the 9 PSFs, max RMSE/peak vs the finest, max RMSE/peak vs 2N)."""
    results = {}
    for n in samples:
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            data = fraunhofer(P.pupil_function(lens, FIELDS, WAVELENGTHS, n), 0.5, 160)
            times.append(time.perf_counter() - start)
        results[n] = (data, statistics.median(times))
    ref = results[samples[-1]][0]
    peak = ref.max(axis=(1, 2))
    rows = []
    for i, n in enumerate(samples):
        data, sec = results[n]
        err = float((np.sqrt(np.mean((data - ref) ** 2, axis=(1, 2))) / peak).max())
        nxt = results[samples[i + 1]][0] if i + 1 < len(samples) else None
        dbl = float((np.sqrt(np.mean((data - nxt) ** 2, axis=(1, 2))) / nxt.max(axis=(1, 2))).max()) if nxt is not None else float("nan")
        rows.append((n, sec, err, dbl))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--skip-grid", action="store_true")
    args = ap.parse_args()
    lens = Lens.load("solas-doublet")
    psf(lens, (0, 0), 531.0)  # compile kernels once
    print(f"machine: {os.cpu_count()} cores\n")
    if not args.skip_grid:
        t = grid_seconds(lens, args.repeats)
        print("| job | median (s) | runs (s) |\n|---|---|---|")
        print(f"| 32×32 grid × 3 wavelengths, 160×160 Fraunhofer PSFs, pupil {DEFAULT_PUPIL_SAMPLES}² | "
              f"{statistics.median(t):.1f} | {', '.join(f'{x:.1f}' for x in t)} |")
        print(f"| the same, all 1024 fields traced (symmetry unused) | {all_fields_seconds(lens):.1f} | 1 run |\n")
    print("| pupil samples N | median seconds (9 PSFs) | max RMSE/peak vs N=512 | max RMSE/peak, N vs 2N |\n|---|---|---|---|")
    for n, sec, err, dbl in sampling_sweep(lens):
        print(f"| {n} | {sec:.2f} | {err:.2e} | {dbl:.2e} |")


if __name__ == "__main__":
    main()
