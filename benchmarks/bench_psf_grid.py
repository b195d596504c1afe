"""PSF-grid speed and pupil-sampling error against run time for the SOLAS doublet, and a lens as built against
the same lens on one axis.

Run: .venv/bin/python benchmarks/bench_psf_grid.py [--repeats 5] [--skip-grid] [--skip-as-built] [--all-fields]
Prints Markdown tables: the 32×32×3 grid (656/531/486 nm, 160×160 Fraunhofer PSFs at 0.5 µm, pupil 128²,
the sampling-error estimate on) and the 8×8×3 one in process (kernels compiled) and the 32×32×3 as the
`psf-grid` command (a fresh process: imports, kernels, the grid, the EXR), medians and runs, with the
command's peak memory; then the Cooke triplet as built (`as_built_lens`: every field traced) against the Cooke
triplet, the 32×32×3 geometric grid and the 8×8×3 Fraunhofer one, medians and their ratios (issue 40's
bound: the as-built geometric grid within 2.5× the symmetric one's time); then the pupil-sampling error
against run time; and the figures `run_all.py`
compares run to run (and sets the README's headline from, on an idle machine).
"""

from __future__ import annotations

import argparse
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from as_built_lens import cooke_as_built
from bench_grid_end_to_end import command
from figures import figure

from solas_mi import Lens
from solas_mi.optics import pupil as P
from solas_mi.psf import psf, psf_grid
from solas_mi.psf.fraunhofer import fraunhofer
from solas_mi.psf.methods import compute
from solas_mi.psf.registry import DEFAULT_PUPIL_SAMPLES

FIELDS = np.array([[0.0, 0.0], [0.0, 2.0], [0.0, -2.0]] * 3)
WAVELENGTHS = np.repeat([486.0, 531.0, 656.0], 3)
KW = dict(wavelengths_nm=[656.0, 531.0, 486.0], pitch_um=0.5, size=160)


def grid_seconds(lens: Lens, n: int, repeats: int, method: str = "fraunhofer") -> list[float]:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        psf_grid(lens, grid=(n, n), method=method, **KW)
        times.append(time.perf_counter() - start)
    return times


def as_built_against_symmetric(repeats: int) -> None:
    """Print the grids of the Cooke triplet as built and of the Cooke triplet (the same lens on one axis, its
    mirror-image fields computed once) side by side, medians and runs, and each pair's ratio; the
    geometric pair's as-built time and ratio as figures."""
    pairs = {"32×32×3 geometric grid": (32, "geometric"), "8×8×3 Fraunhofer grid": (8, "fraunhofer")}
    lenses = {"as built": cooke_as_built(), "on one axis": Lens.load("cooke-triplet")}
    for lens in lenses.values():  # compile both lenses' kernels first
        for method in ("geometric", "fraunhofer"):
            grid_seconds(lens, 2, 1, method)
    print("\nThe Cooke triplet as built (middle element decentred and tilted, a toroid last) against it on one axis")
    print("\n| grid | as built, median (s) | on one axis, median (s) | ratio | runs as built / on one axis (s) |")
    print("|---|---|---|---|---|")
    medians = {}
    for name, (n, method) in pairs.items():
        built, axis = (grid_seconds(lens, n, repeats, method) for lens in lenses.values())
        medians[name] = statistics.median(built), statistics.median(axis)
        (a, b), runs = medians[name], f"{', '.join(f'{x:.2f}' for x in built)} / {', '.join(f'{x:.2f}' for x in axis)}"
        print(f"| {name} | {a:.2f} | {b:.2f} | {a / b:.1f} | {runs} |")
    built, axis = medians["32×32×3 geometric grid"]
    figure("psf_grid_as_built_geometric_32x32x3_s", built, "s")
    figure("psf_grid_as_built_geometric_ratio", built / axis, "x")


def command_seconds(repeats: int) -> tuple[list[float], float]:
    """The `psf-grid` command's wall seconds per run and its peak memory (MB, the largest run's)."""
    with tempfile.TemporaryDirectory() as tmp:
        times = [command(Path(tmp)) for _ in range(repeats)]
    return times, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024


def all_fields_seconds(lens: Lens) -> float:
    """The same 32×32×3 grid with every field traced (no use of the lens's mirror symmetry)."""
    fx = np.linspace(-2.0, 2.0, 32, endpoint=False) + 2.0 / 32
    fields = np.stack(np.meshgrid(fx, fx), axis=-1).reshape(-1, 2)
    start = time.perf_counter()
    for w in (656.0, 531.0, 486.0):
        for a in range(0, len(fields), 64):
            compute(
                lens, fields[a : a + 64], np.full(64, w), 0.5, 160, "fraunhofer", pupil_samples=DEFAULT_PUPIL_SAMPLES
            )
    return time.perf_counter() - start


def sampling_sweep(
    lens: Lens,
    samples=(32, 64, 128, 256, 512),
    repeats: int = 3,
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
        dbl = (
            float((np.sqrt(np.mean((data - nxt) ** 2, axis=(1, 2))) / nxt.max(axis=(1, 2))).max())
            if nxt is not None
            else float("nan")
        )
        rows.append((n, sec, err, dbl))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--skip-grid", action="store_true")
    ap.add_argument("--skip-as-built", action="store_true")
    ap.add_argument("--all-fields", action="store_true", help="also the grid with every field traced (minutes)")
    args = ap.parse_args()
    lens = Lens.load("solas-doublet")
    psf(lens, (0, 0), 531.0)  # compile kernels once
    if not args.skip_grid:
        grid_seconds(lens, 8, 1)
        rows = {
            "32×32×3 grid, in process": grid_seconds(lens, 32, args.repeats),
            "8×8×3 grid, in process": grid_seconds(lens, 8, args.repeats),
        }
        rows["32×32×3 grid, the `psf-grid` command"], peak_mb = command_seconds(args.repeats)
        print(f"Fraunhofer PSFs of 160×160 at 0.5 µm, pupil {DEFAULT_PUPIL_SAMPLES}², the sampling-error estimate on\n")
        print("| job | median (s) | runs (s) |\n|---|---|---|")
        for name, t in rows.items():
            print(f"| {name} | {statistics.median(t):.2f} | {', '.join(f'{x:.2f}' for x in t)} |")
        if args.all_fields:
            print(f"| the same, all 1024 fields traced (symmetry unused) | {all_fields_seconds(lens):.1f} | 1 run |")
        print(
            f"\nthe command's peak memory: {peak_mb:.0f} MB (the grid's PSFs alone: "
            f"{3 * 32 * 32 * 160 * 160 * 4 / 2**20:.0f} MB)\n"
        )
        for key, name in (
            ("psf_grid_32x32x3_s", "32×32×3 grid, in process"),
            ("psf_grid_8x8x3_s", "8×8×3 grid, in process"),
            ("psf_grid_command_s", "32×32×3 grid, the `psf-grid` command"),
        ):
            figure(key, statistics.median(rows[name]), "s")
        figure("psf_grid_command_peak_mb", peak_mb, "MB")
    if not args.skip_as_built:
        as_built_against_symmetric(args.repeats)
    print(
        "\n| pupil samples N | median seconds (9 PSFs) | max RMSE/peak vs N=512 | max RMSE/peak, N vs 2N |\n|---|---|---|---|"
    )
    for n, sec, err, dbl in sampling_sweep(lens):
        print(f"| {n} | {sec:.2f} | {err:.2e} | {dbl:.2e} |")


if __name__ == "__main__":
    main()
