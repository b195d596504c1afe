"""Speed of the depth-aware convolution (`degrade --depth`): a 1280×960 RGB frame with its depth map,
8 depth nodes, beside the single-depth interp on one node's grid, in the same process.

Run: .venv/bin/python benchmarks/bench_depth.py [--repeats 3] [--nodes 8]
The doublet's grid over distance (32×24 field nodes over ±2° × ±1.5°, 656/531/486 nm, geometric, 160×160
at 0.5 µm — the single-distance benchmark's kernel size; nodes evenly spaced in 1/distance from
infinity to 5 m) is computed once and cached in out/bench/. The frame: a street-like depth map (the
ground from 200 m at the horizon to 5 m at the bottom row, evenly in 1/distance, a facade at 140 m
above it, a box at 12 m and a post at 25 m). Prints the medians (s), the cores other processes used meanwhile (timings are
only good near 0) and the grid's computing time when it was computed.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_convolution import CACHE, WAVELENGTHS, busy_seconds, test_image

W, H = 1280, 960


def depth_map() -> np.ndarray:
    """Street-like depth (m): the ground below the horizon (row H/2), from 200 m there to 5 m at the bottom
    row evenly in 1/distance (every node gets pixels), a facade at 140 m above, a box at 12 m, a post at 25 m."""
    below = np.clip((np.arange(H)[:, None] + 0.5 - H / 2) / (H / 2), 0.0, 1.0)
    ground = 1.0 / (1 / 200 + below * (1 / 5 - 1 / 200))
    d = np.broadcast_to(np.where(below > 0, ground, 140.0), (H, W)).copy()
    d[300:800, 100:400] = 12.0  # a box
    d[:, 900:930] = 25.0  # a post
    return d


def grid(nodes: int):
    from solas_mi import Lens
    from solas_mi.psf.depth import DepthGrid, depth_grid, read_grid
    from solas_mi.psf.spec import GridSpec, inverse_spaced

    path = CACHE / f"solas_doublet_depth{nodes}_32x24_geometric_160.exr"
    if path.is_file():
        return read_grid(str(path)), None
    print(f"computing the grid over {nodes} distances once (cached in {path})", file=sys.stderr, flush=True)
    start = time.perf_counter()
    g = depth_grid(
        Lens.load("solas-doublet"),
        GridSpec(
            grid=(24, 32),
            wavelengths_nm=WAVELENGTHS,
            field_range_deg=(2.0, 1.5),
            method="geometric",
            pitch_um=0.5,
            size=160,
            distances_m=inverse_spaced(nodes, 5.0),
        ),
    )
    seconds = time.perf_counter() - start
    CACHE.mkdir(parents=True, exist_ok=True)
    g.write(str(path))
    assert isinstance(read_grid(str(path)), DepthGrid)
    return g, seconds


def timed(fn, repeats: int) -> tuple[float, list[float], float]:
    fn()  # warm-up
    times = []
    busy, own, wall = busy_seconds(), sum(os.times()[:2]), time.perf_counter()
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    others = (busy_seconds() - busy - (sum(os.times()[:2]) - own)) / (time.perf_counter() - wall)
    return statistics.median(times), times, others


def main() -> None:
    from solas_mi.convolution.depth import degrade_depth
    from solas_mi.convolution.methods import degrade

    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--nodes", type=int, default=8)
    args = ap.parse_args()
    g, grid_seconds = grid(args.nodes)
    image, depth = test_image(W, H), depth_map()
    meta: dict = {}
    degrade_depth(image, depth, g, meta=meta)
    print(
        f"machine: {os.cpu_count()} cores; grid over {args.nodes} distances {meta['distances_m']} m"
        + (f", computed in {grid_seconds:.0f} s" if grid_seconds else " (cached)")
    )
    print(f"pixels per node: {[round(p) for p in meta['pixels_per_node']]}\n")
    print("| case | median (s) | runs (s) | other processes' load (cores) |\n|---|---|---|---|")
    cases = {
        "1280×960 RGB, interp 32×24, one distance": lambda: degrade(image, g.layers[0], "interp"),
        f"1280×960 RGB + depth, {args.nodes} nodes, occlusion filled": lambda: degrade_depth(image, depth, g),
        f"1280×960 RGB + depth, {args.nodes} nodes, occlusion none": lambda: degrade_depth(
            image, depth, g, occlusion="none"
        ),
    }
    for name, fn in cases.items():
        median, times, others = timed(fn, args.repeats)
        print(
            f"| {name} | {median:.2f} | {', '.join(f'{t:.2f}' for t in times)} | {max(0.0, others):.2f} |", flush=True
        )


if __name__ == "__main__":
    main()
