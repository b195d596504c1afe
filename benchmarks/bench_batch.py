"""Throughput of `solas-mi batch degrade`: 1280×960 RGB images (copies of scenes/images/rocket.png)
degraded with the doublet's 32×32 grid (656/531/486 nm, Fraunhofer, 160×160 PSFs at 0.5 µm,
`interp`), on 1 and 2 local worker processes and on a Dask LocalCluster of 1 and 2 workers.

With --render: the same images rendered through the doublet (`batch render`, the image-object scene,
RENDER_SENSOR at RENDER_SPP spp, srgb) instead, on the same four runners; no grid.

Run: .venv/bin/python benchmarks/bench_batch.py [--images 16] [--repeats 3] [--render]
The grid is computed once through the batch's own cache (out/bench/batch-cache). Each run is a fresh
batch into a fresh folder, timed from the call to the end (worker start-up, grid loading or
scattering, reading, degrading, writing EXR + PNG, manifest). Prints a Markdown table of the median
images/s and the median seconds one item takes inside its worker.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import time
from pathlib import Path

from solas_mi import Lens
from solas_mi.batch import GridCache, degrade_batch, render_batch
from solas_mi.psf.spec import GridSpec

ROOT = Path(__file__).resolve().parent.parent
WORK = ROOT / "out" / "bench"
GRID = dict(grid=(32, 32), wavelengths_nm=(656.0, 531.0, 486.0), size=160, pitch_um=0.5)  # the doublet's
RENDER_SENSOR, RENDER_SPP = "320x240", 16
CASES = [
    ("local processes", None, 1),
    ("local processes", None, 2),
    ("Dask LocalCluster", "local", 1),
    ("Dask LocalCluster", "local", 2),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--images", type=int, default=16)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--render", action="store_true", help="batch render instead of batch degrade")
    args = parser.parse_args()
    images = WORK / "batch-images"
    shutil.rmtree(images, ignore_errors=True)
    images.mkdir(parents=True)
    for i in range(args.images):
        shutil.copy(ROOT / "scenes" / "images" / "rocket.png", images / f"rocket{i:03d}.png")
    if args.render:

        def run(out, workers, dask):
            return render_batch(
                [images],
                out,
                lens="solas-doublet",
                sensor=RENDER_SENSOR,
                spp=RENDER_SPP,
                workers=workers,
                dask=dask,
                progress=False,
            )
    else:
        cache = GridCache(WORK / "batch-cache")
        start = time.perf_counter()
        grid_path, hit, _ = cache.get(Lens.load("solas-doublet"), GridSpec(**GRID))
        print(f"grid {grid_path.name}: {'cache hit' if hit else 'computed'} in {time.perf_counter() - start:.1f} s")

        def run(out, workers, dask):
            return degrade_batch([images], out, psf_grid=grid_path, workers=workers, dask=dask, progress=False)

    print(f"| runner | workers | images/s (median of {args.repeats}) | s per image in a worker |")
    print("|---|---|---|---|")
    for name, dask, workers in CASES:
        rates, items = [], []
        for _r in range(args.repeats):
            out = WORK / "batch-out"
            shutil.rmtree(out, ignore_errors=True)
            result = run(out, workers, dask)
            assert not result.failed, result.failed[0].error
            rates.append(args.images / result.seconds)
            items.extend(job.seconds for job in result.jobs)
        print(f"| {name} | {workers} | {statistics.median(rates):.2f} | {statistics.median(items):.2f} |", flush=True)


if __name__ == "__main__":
    main()
