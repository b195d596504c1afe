"""The mono variant against the spectral one for jobs of one wavelength (`render.mitsuba.variant_for`).

Run: .venv/bin/python benchmarks/bench_mono.py [--repeats 5] [--jobs image,street]
- render-image: `render.image.render_image` (what `solas-mi render-image` calls) of the bundled
  rocket.png through the doublet at mono:450, 640×480 at 64 spp, Fresnel transmit: wall-clock seconds
  of the whole call (scene written, loaded, rendered) in llvm_ad_spectral and llvm_ad_mono.
- street: the street experiment's grey scene through `lens_camera` at mono:531, 640×480 at 64 spp
  (`render.stock.render_scene`, Mitsuba's `path`), the two variants' films (specfilm line / luminance),
  wall-clock seconds of loading and rendering.
After one warm-up render per variant (kernels compiled), the variants alternate, `repeats` runs each,
so both see the same load of the shared cores; the table gives medians, min–max, and the speed-up
(spectral median / mono median) of wall-clock and of CPU seconds (the process's, all threads: less
sensitive to other jobs on the cores). The 1-minute load average is printed before and after, each round's
times on stderr as it ends.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path
from statistics import median

from solas_mi import Lens
from solas_mi.resources import resource_dir

VARIANTS = ("llvm_ad_spectral", "llvm_ad_mono")


def image_job(lens):
    from solas_mi.render.image import render_image

    image = str(resource_dir("scenes") / "images" / "rocket.png")

    def run(variant: str) -> tuple[float, float]:
        start, cpu = time.perf_counter(), time.process_time()
        render_image(
            lens, image, sensor=(480, 640), spp=64, response="mono:450", fresnel="transmit", variant=variant, seed=1
        )
        return time.perf_counter() - start, time.process_time() - cpu

    return "render-image, doublet, 640×480, 64 spp, mono:450", run


def street_job(lens, tmp: Path):
    from solas_mi.experiments.street.framings import framing
    from solas_mi.experiments.street.run import SCENE, experiment_scene
    from solas_mi.render.stock import render_scene
    from solas_mi.render.user_scene import default_pitch_um, load

    fov, w, h, spp = float(lens.field_deg), 640, 480, 64
    params = {k: v for k, v in framing(lens).params(2 * fov, w, h, spp).items() if k != "fov"}
    pitch = default_pitch_um(lens, fov, "x", w, h)
    xmls = {v: experiment_scene(SCENE, tmp / v, 531.0, spectral="spectral" in v) for v in VARIANTS}

    def run(variant: str) -> tuple[float, float]:
        start, cpu = time.perf_counter(), time.process_time()
        scene = load(xmls[variant], variant, lens, params, response="mono:531", pitch_um=pitch)
        render_scene(scene, spp, seed=1)
        return time.perf_counter() - start, time.process_time() - cpu

    return "lens_camera, street scene, 640×480, 64 spp, mono:531", run


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--jobs", default="image,street", help="which jobs: image, street (comma-separated)")
    args = ap.parse_args()
    lens = Lens.load("solas-doublet")
    print(f"load average before: {os.getloadavg()[0]:.2f}", flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        make = {"image": lambda: image_job(lens), "street": lambda: street_job(lens, Path(tmp))}
        jobs = [make[name.strip()]() for name in args.jobs.split(",")]
        rows = []
        for name, run in jobs:
            for v in VARIANTS:
                run(v)  # warm-up: kernels compiled
            times = {v: [] for v in VARIANTS}
            for k in range(args.repeats):
                for v in VARIANTS:
                    times[v].append(run(v))
                print(
                    f"  {name}, round {k + 1}: "
                    + ", ".join(  # progress: stderr (stdout holds the results)
                        f"{v} {times[v][-1][0]:.2f} s ({times[v][-1][1]:.2f} s CPU)" for v in VARIANTS
                    ),
                    file=sys.stderr,
                    flush=True,
                )
            rows.append((name, times))
    print(f"load average after: {os.getloadavg()[0]:.2f}\n")
    print(
        "| job | variant | wall median (s) | wall min–max (s) | speed-up | CPU median (s) | CPU min–max (s) | "
        "speed-up |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name, times in rows:
        cells = []
        for v in VARIANTS:
            row = []
            for i in (0, 1):  # wall clock, CPU
                t, base = [r[i] for r in times[v]], median(r[i] for r in times[VARIANTS[0]])
                row.append(f"{median(t):.2f} | {min(t):.2f}–{max(t):.2f} | {base / median(t):.2f}×")
            cells.append(f"| {name} | {v} | {' | '.join(row)} |")
        print("\n".join(cells))


if __name__ == "__main__":
    main()
