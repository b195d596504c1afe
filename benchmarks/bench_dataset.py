"""Throughput of a dataset's frames: a 1920×1080 frame through each stage of `solas-mi batch degrade` with
a camera, alone (read the PNG → degrade with the doublet's 32×32×3 grid, `interp` → write the degraded EXR
and PNG → the sensor (AR0132AT, auto exposure) → the image processor (default) → write the RAW EXR and
the developed PNG), then the batch itself on 1 and 2 local workers against the sum of the stages.

Run: .venv/bin/python benchmarks/bench_dataset.py [--frames 8] [--repeats 3]
Prints each stage's median seconds, frames/s and share of the sum; the batch's frames/s (median of the
repeats; worker start-up, grid loading and the manifest included) against what the sum of the stages
allows (w workers: min(w / seconds, cores / CPU seconds), the stages timed on each worker's share of the
cores, `threads.share`); and the figures `run_all.py` compares run to run.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_convolution import test_image
from figures import figure

ROOT = Path(__file__).resolve().parent.parent
WORK = ROOT / "out" / "bench" / "dataset"
W, H = 1920, 1080
GRID = dict(grid=(32, 32), wavelengths_nm=(656.0, 531.0, 486.0), size=160, pitch_um=0.5)  # the doublet's
WORKERS = (1, 2)
TARGET = 1.3  # the batch's time per frame may be this much more than the sum of its stages


def setup(frames: int) -> tuple[Path, Path, object]:
    """The test frames (8-bit sRGB PNGs), the grid (through the batch's cache) and the camera."""
    from solas_mi import Lens
    from solas_mi.batch import GridCache
    from solas_mi.imageio import write_png
    from solas_mi.isp.camera import load_camera
    from solas_mi.psf.spec import GridSpec
    from solas_mi.sensor.auto_exposure import parse_exposure

    images = WORK / "frames"
    shutil.rmtree(images, ignore_errors=True)
    images.mkdir(parents=True)
    write_png(str(images / "frame000.png"), test_image(W, H))
    for i in range(1, frames):
        shutil.copy(images / "frame000.png", images / f"frame{i:03d}.png")
    grid_path, _, _ = GridCache(ROOT / "out" / "bench" / "batch-cache").get(
        Lens.load("solas-doublet"), GridSpec(**GRID)
    )
    return images, grid_path, load_camera("ar0132at", parse_exposure("auto"), "default")


def stages(images: Path, grid_path: Path, camera, repeats: int, threads: int) -> dict[str, tuple[float, float]]:
    """Median (wall, CPU) seconds of each stage of one frame, as a batch item does it on `threads` threads (a
    worker's share of the cores, `threads.use_share`; CPU: all the process's threads). The camera takes the
    degraded image as the item does (`batch.work.as_written`, `sensor.commands.as_irradiance`: float64, negative
    values as no light) and warns of saturation as it does."""
    from solas_mi.batch.work import as_written
    from solas_mi.convolution import degrade
    from solas_mi.convolution.output import write_output
    from solas_mi.imageio import read_image
    from solas_mi.isp.camera import write_frame
    from solas_mi.isp.pipeline import develop
    from solas_mi.psf.depth import read_grid
    from solas_mi.sensor.auto_exposure import exposure_seconds
    from solas_mi.sensor.capture import capture
    from solas_mi.sensor.commands import as_irradiance, clipping_warning
    from solas_mi.threads import use_share

    use_share(threads)
    grid = read_grid(str(grid_path))
    out = WORK / "stages"
    out.mkdir(parents=True, exist_ok=True)
    source = images / "frame000.png"
    state: dict = {}

    def sensor() -> None:
        irradiance = as_irradiance(*as_written(state["out"], {}, "exr"), "f.exr", camera.scale)[0]
        seconds = exposure_seconds(camera.exposure_ms, camera.sensor, irradiance)[0]
        state["raw"] = capture(camera.sensor, irradiance, seconds, camera.seed, 1)
        clipping_warning(camera.sensor, state["raw"], 1e3 * seconds, "f_raw.exr")

    steps = {
        "read": lambda: state.update(image=read_image(source, linearize=True)),
        "degrade (interp, 32×32 grid)": lambda: state.update(out=degrade(state["image"], grid, "interp", "edge")),
        "write degraded EXR + PNG": lambda: write_output(
            out / "f.exr", out / "f.png", state["out"], None, {}, "exr", source
        ),
        "sensor (auto exposure)": sensor,
        "image processor": lambda: state.update(frame=develop(state["raw"], camera.sensor, camera.isp)[0]),
        "write RAW EXR + frame PNG": lambda: write_frame(out / "f_raw.exr", state["raw"], state["frame"], {}),
    }
    times = {name: [] for name in steps}
    for _ in range(repeats + 1):  # the first round warms up (imports, first calls)
        for name, step in steps.items():
            wall, cpu = time.perf_counter(), time.process_time()
            step()
            times[name].append((time.perf_counter() - wall, time.process_time() - cpu))
    return {name: tuple(statistics.median(v) for v in zip(*t[1:])) for name, t in times.items()}


def batch(images: Path, grid_path: Path, camera, workers: int, repeats: int) -> tuple[float, float]:
    """(frames/s of the whole batch, median seconds an item takes in its worker), medians of the repeats."""
    from solas_mi.batch import degrade_batch
    from solas_mi.convolution.spec import DegradeSpec

    rates, items = [], []
    for _ in range(repeats):
        out = WORK / "batch-out"
        shutil.rmtree(out, ignore_errors=True)
        result = degrade_batch(
            [images], out, DegradeSpec(camera=camera), psf_grid=grid_path, workers=workers, progress=False
        )
        assert not result.failed, result.failed[0].error
        rates.append(len(result.jobs) / result.seconds)
        items.extend(job.seconds for job in result.jobs)
    return statistics.median(rates), statistics.median(items)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    images, grid_path, camera = setup(args.frames)
    from solas_mi.threads import cores, share

    sums = {}  # threads → the stages' (wall, CPU) seconds on that many threads, each worker's share of the cores
    for threads in sorted({share(w) for w in WORKERS}, reverse=True):
        seconds = stages(images, grid_path, camera, args.repeats, threads)
        sums[threads] = tuple(sum(v[i] for v in seconds.values()) for i in (0, 1))
        if threads == share(1):
            print(
                f"One {W}×{H} frame, stage by stage (median of {args.repeats}; CPU: the seconds of all its threads):\n"
            )
            print("| stage | seconds | CPU seconds | frames/s | share |\n|---|---|---|---|---|")
            for name, (s, c) in seconds.items():
                print(f"| {name} | {s:.3f} | {c:.3f} | {1 / s:.2f} | {s / sums[threads][0]:.0%} |")
        print(
            f"| sum of the stages on {threads} thread(s) | {sums[threads][0]:.3f} | {sums[threads][1]:.3f} "
            f"| {1 / sums[threads][0]:.2f} | 100% |"
        )
    wall = sums[share(1)][0]
    print(
        f"\nThe batch of {args.frames} frames (`batch degrade` with the camera; median of {args.repeats}); the stages "
        f"allow w workers min(w / seconds, {cores()} cores / CPU seconds) frames/s, the stages timed on each worker's "
        "share of the cores (`threads.share`: as many threads as it runs):\n"
    )
    print("| workers | frames/s | the stages allow | allowed / batch | s per item in a worker |\n|---|---|---|---|---|")
    rates = {}
    for workers in WORKERS:
        rates[workers], item = batch(images, grid_path, camera, workers, args.repeats)
        allowed = min(workers / sums[share(workers)][0], cores() / sums[share(workers)][1])
        print(
            f"| {workers} | {rates[workers]:.3f} | {allowed:.3f} | {allowed / rates[workers]:.2f} (target ≤ {TARGET}) "
            f"| {item:.2f} |",
            flush=True,
        )
    print()  # the figures after the table, not between its rows
    for workers, rate in rates.items():
        figure(f"dataset_batch_{workers}_workers", rate, "frames/s")
    figure("dataset_stage_sum", wall, "s")


if __name__ == "__main__":
    main()
