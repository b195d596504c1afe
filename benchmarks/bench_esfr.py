"""Speed of the sharpness metrics: e-SFR of a 100×100 ROI, natural-scene SFR of a 1280×960 image.

Run: .venv/bin/python benchmarks/bench_esfr.py   (prints a Markdown table, medians of several runs, and the
figures `run_all.py` compares run to run)
"""

from __future__ import annotations

import math
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from figures import figure

from solas_mi.metrics.esfr import esfr
from solas_mi.metrics.nssfr import natural_scene_sfr
from solas_mi.metrics.targets import Square, slanted_edge, slanted_squares


def median_seconds(fn: Callable[[], object], runs: int) -> float:
    fn()  # warm-up
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def scene(shape: tuple[int, int], blur_growth: float, seed: int) -> np.ndarray:
    """Slanted squares on a 110-px grid, σ growing with the radius (σ = 0.8 + growth·r/R px),
    sensor-like noise and a band of fine texture that the edge filters must reject."""
    rows, cols = shape
    big_r = math.hypot(rows, cols) / 2
    squares = []
    for i, y in enumerate(range(70, rows - 50, 110)):
        for j, x in enumerate(range(70, cols - 50, 110)):
            r = math.hypot(x - (cols - 1) / 2, y - (rows - 1) / 2) / big_r
            squares.append(Square(x, y, 64, 6.0 if (i + j) % 2 else -8.0, 0.8 + blur_growth * r, 0.15 + 0.1 * (j % 3)))
    img = slanted_squares(shape, squares, background=0.7, noise=0.003, seed=seed, supersample=2)
    texture = np.random.default_rng(seed).uniform(0.3, 0.6, (6, cols // 4)).repeat(4, 0).repeat(4, 1)
    img[rows // 2 - 12 : rows // 2 + 12, : texture.shape[1]] = texture
    return img


def main() -> None:
    roi = slanted_edge((100, 100), 5.0, 1.0, noise=0.005, seed=1)
    sharp = scene((960, 1280), 1.0, seed=2)
    soft = scene((960, 1280), 2.5, seed=2)
    report = natural_scene_sfr(sharp)
    rows = [  # (name, figure, median seconds, runs, target seconds)
        ("e-SFR, 100×100 ROI, 2023 mode", "esfr_roi_2023_s", median_seconds(lambda: esfr(roi), 200), 200, 0.005),
        (
            "e-SFR, 100×100 ROI, 2017 mode",
            "esfr_roi_2017_s",
            median_seconds(lambda: esfr(roi, mode="2017"), 200),
            200,
            0.005,
        ),
        (
            f"natural-scene SFR, 1280×960 ({len(report.rois)} ROIs)",
            "nssfr_s",
            median_seconds(lambda: natural_scene_sfr(sharp), 5),
            5,
            5.0,
        ),
        (
            "natural-scene SFR, 1280×960, --compare",
            "nssfr_compare_s",
            median_seconds(lambda: natural_scene_sfr(sharp, compare=soft), 5),
            5,
            5.0,
        ),
    ]
    print("| benchmark | median | runs | target | met |")
    print("|---|---|---|---|---|")
    for name, _, sec, runs, target in rows:
        shown = f"{sec * 1e3:.2f} ms" if sec < 1 else f"{sec:.2f} s"
        goal = f"≤ {target * 1e3:.0f} ms" if target < 1 else f"≤ {target:.0f} s"
        print(f"| {name} | {shown} | {runs} | {goal} | {'yes' if sec <= target else 'NO'} |")
    print()
    for _, key, sec, _, _ in rows:
        figure(key, sec, "s")


if __name__ == "__main__":
    main()
