"""A population through PSF grids: N Cooke triplets drawn from the shipped tolerance file, each one's 16×12×3
PSF grid (the lens's three wavelengths, `GridSpec`'s defaults otherwise), on local processes or Dask, as
`batch degrade --lens-population` computes them (one grid per lens instance through the `GridCache`).
Issue 41's target: 200 lenses in at most 10 minutes on 2 cores.

Run: .venv/bin/python benchmarks/bench_tolerance.py [--lenses 200] [--workers 2] [--dask local|ADDRESS]
     [--estimate 4]  (with --estimate K: K lenses only, the time for --lenses extrapolated from them)
Prints a Markdown table (lenses, workers, seconds, per lens) and the figures `run_all.py` compares run to run.
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import statistics
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from figures import figure

from solas_mi import Lens
from solas_mi.optics import tolerance as tol
from solas_mi.psf.spec import GridSpec

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "scenes" / "tolerances" / "cooke-triplet.toml"
GRID = (16, 12)
SEED = 41


def one_grid(index: int, cache_dir: str) -> tuple[float, float]:
    """(wall, CPU) seconds to draw lens `index` of the population and compute its grid into the cache (a fresh
    worker's first grid includes its kernels). CPU seconds (every thread of the worker) do not depend on what
    else loads the machine: with W workers on C cores the wall time is about their sum / min(W, C)."""
    from solas_mi.batch import GridCache

    start, cpu = time.perf_counter(), time.process_time()
    lens = Lens.load("cooke-triplet")
    drawn, _ = tol.draw(lens, tol.read_spec(lens, SPEC), SEED, index)
    GridCache(cache_dir).get(drawn, GridSpec(grid=GRID, wavelengths_nm=drawn.wavelengths_nm))
    return time.perf_counter() - start, time.process_time() - cpu


def run_local(count: int, workers: int, cache_dir: str) -> list[tuple[float, float]]:
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        return list(pool.map(one_grid, range(count), [cache_dir] * count))


def run_dask(count: int, workers: int, address: str, cache_dir: str) -> list[tuple[float, float]]:
    from distributed import Client, LocalCluster

    cluster = (
        LocalCluster(n_workers=workers, threads_per_worker=1, dashboard_address=None) if address == "local" else None
    )
    with Client(cluster or address) as client:
        futures = client.map(one_grid, range(count), [cache_dir] * count, pure=False)
        seconds = client.gather(futures)
    if cluster is not None:
        cluster.close()
    return seconds


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--lenses", type=int, default=200, help="the population (default 200)")
    ap.add_argument("--workers", type=int, default=2, help="local processes or LocalCluster workers (default 2)")
    ap.add_argument("--dask", help="a Dask scheduler's address, or local (default: local processes)")
    ap.add_argument("--estimate", type=int, help="compute this many lenses and extrapolate to --lenses")
    args = ap.parse_args()
    count = args.estimate or args.lenses
    with tempfile.TemporaryDirectory() as cache_dir:
        start = time.perf_counter()
        if args.dask:
            seconds = run_dask(count, args.workers, args.dask, cache_dir)
        else:
            seconds = run_local(count, args.workers, cache_dir)
        wall = time.perf_counter() - start
    steady = statistics.median(s for s, _ in seconds[args.workers :] or seconds)  # past each worker's first grid
    cpu = statistics.median(c for _, c in seconds)
    total = wall if not args.estimate else wall + (args.lenses - count) * steady / args.workers
    where = f"Dask {args.dask}" if args.dask else "local processes"
    print(f"Cooke triplet population ({SPEC.name}, seed {SEED}): {GRID[0]}×{GRID[1]}×3 PSF grids, {where}\n")
    print(
        "| lenses | workers | wall (s) | per grid, median wall (s) | per grid, median CPU (s) | CPU-bound "
        f"{args.lenses} lenses on {os.cpu_count()} cores (s) | target (s) |\n|---|---|---|---|---|---|---|"
    )
    label = f"{count} (→ {args.lenses} estimated)" if args.estimate else f"{count}"
    bound = args.lenses * cpu / min(args.workers, os.cpu_count() or 1)
    print(f"| {label} | {args.workers} | {total:.0f} | {steady:.1f} | {cpu:.1f} | {bound:.0f} | 600 |")
    figure("tolerance_population_s", total, "s")
    figure("tolerance_grid_s", steady, "s")
    figure("tolerance_grid_cpu_s", cpu, "s")


if __name__ == "__main__":
    main()
