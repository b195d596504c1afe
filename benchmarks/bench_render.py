"""Direct spectral render through the doublet's geometry (`solas-mi render-image`): speed, noise
against run time, and the cap-mesh ring count's accuracy/speed trade-off.

Run: .venv/bin/python benchmarks/bench_render.py [--quick | --stock]
- Speed: the bundled 1280×960 photograph, llvm_ad_spectral, samples per second at 64 spp.
- Noise: relative RMSE = RMS(a − b)/√2 / RMS(mean) of two renders with different seeds, for spp
  4…1024, responses `lines` and `srgb`, on the 320×240 centre of the 1280×960 sensor (same pitch;
  per-pixel noise does not depend on the sensor size). Time = the 1280×960 render time at that spp
  from the measured rate.
- Rings: the scene PSF's worst centroid and RMS-radius error against the tracer (0°, ±2°,
  486/531/656 nm) and the render rate, per ring count.
- Stock (`--stock`, only this): the shipped scene (scenes/solas_doublet/scene.xml, srgb, the bundled
  photograph) on its 320×240 centre, 64 spp: samples per second of Mitsuba's `path` (`mi.render`,
  hdrfilm, stratified sampler) and of solas-mi's loop, median of 3 after a warm-up render, and each
  one's per-pixel noise (relative RMSE between two seeds / √2; stock divided by its flat white).
Prints Markdown tables.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

from solas_mi import Lens
from solas_mi.imageio import read_image
from solas_mi.optics.camera import camera_for
from solas_mi.render.image import render_image
from solas_mi.render.mitsuba import load_scene, mitsuba
from solas_mi.resources import resource_dir


def noise_table(lens, image, camera, spps, response):
    rows = []
    for spp in spps:
        a = render_image(
            lens, image, sensor=(240, 320), pitch_um=camera.pitch_um, spp=spp, response=response, seed=1
        ).image
        b = render_image(
            lens, image, sensor=(240, 320), pitch_um=camera.pitch_um, spp=spp, response=response, seed=2
        ).image
        noise = np.sqrt(np.mean((a - b) ** 2) / 2) / np.sqrt(np.mean((0.5 * (a + b)) ** 2))
        rows.append((spp, noise))
        print(f"  {response} spp {spp}: noise {noise * 100:.2f} %", flush=True)
    return rows


def stock_table(spp: int = 64, size: tuple[int, int] = (320, 240)) -> None:
    """Mitsuba's `path` against solas-mi's loop on the shipped scene: samples/s and noise."""
    from statistics import median

    from solas_mi.render.loop import render

    mi = mitsuba("llvm_ad_spectral")
    scene = mi.load_file(
        str(resource_dir("scenes") / "solas_doublet" / "scene.xml"), width=str(size[0]), height=str(size[1])
    )
    lam = np.arange(380.0, 780.0, 0.05) + 0.025  # hdrfilm's flat white over the camera's wavelengths
    xyz = np.array(mi.cie1931_xyz(mi.Float(lam))).T.sum(axis=0) * 0.05 * mi.MI_CIE_Y_NORMALIZATION
    white = np.array(mi.xyz_to_srgb(mi.Color3f(*(float(v) for v in xyz)))).ravel()
    samples = size[0] * size[1] * spp

    def stock(seed):
        t = time.perf_counter()
        image = np.array(mi.render(scene, spp=spp, seed=seed)) / white
        return image, time.perf_counter() - t

    def loop(seed):
        r = render(scene, spp, seed=seed)
        return r.image, r.seconds

    print(f"\n| engine ({size[0]}×{size[1]}, {spp} spp, srgb) | M samples/s (median of 3) | runs (s) | noise |")
    print("|---|---|---|---|")
    for name, run in (("Mitsuba path (mi.render)", stock), ("solas-mi loop", loop)):
        run(0)  # compile
        runs = [run(seed) for seed in (1, 2, 3)]
        a, b = runs[0][0], runs[1][0]
        noise = np.sqrt(np.mean((a - b) ** 2) / 2) / np.sqrt(np.mean((0.5 * (a + b)) ** 2))
        seconds = [t for _, t in runs]
        print(
            f"| {name} | {samples / median(seconds) / 1e6:.2f} | {', '.join(f'{t:.2f}' for t in seconds)} | "
            f"{noise * 100:.1f} % |",
            flush=True,
        )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer spp, for a smoke run")
    ap.add_argument("--stock", action="store_true", help="only Mitsuba's path integrator against the loop")
    args = ap.parse_args()
    if args.stock:
        return stock_table()
    mitsuba("llvm_ad_spectral")
    lens = Lens.load("solas-doublet")
    image = read_image(resource_dir("scenes") / "images" / "rocket.png")
    camera = camera_for(lens)
    render_image(lens, image, sensor=(96, 128), spp=4, response="lines")  # compile the kernels once
    rates = {}
    for response in ("lines", "srgb"):
        r = render_image(lens, image, sensor=(960, 1280), spp=16 if args.quick else 64, response=response)
        rates[response] = 1280 * 960 * r.spp / r.meta["cpu_seconds"] * os.cpu_count()  # contention-proof
        cores = os.cpu_count()
        print(
            f"1280x960 {response} {r.spp} spp: {r.seconds:.1f} s wall, {r.samples_per_second / 1e6:.2f} M samples/s; "
            f"CPU {r.meta['cpu_seconds']:.1f} s = {1280 * 960 * r.spp / r.meta['cpu_seconds'] * cores / 1e6:.2f} "
            f"M samples/s on {cores} idle cores",
            flush=True,
        )
    spps = (4, 16, 64) if args.quick else (4, 16, 64, 256, 1024)
    print("\n| response | spp | noise (relative RMSE) | 1280×960 time (s) |\n|---|---|---|---|")
    table = {resp: noise_table(lens, image, camera, spps, resp) for resp in ("lines", "srgb")}
    for resp, rows in table.items():
        for spp, noise in rows:
            print(f"| {resp} | {spp} | {noise * 100:.2f} % | {spp * 1280 * 960 / rates[resp]:.0f} |")
    print(
        "\n| cap rings | scene PSF centroid error (µm) | RMS radius error | render rate (M samples/s) |\n|---|---|---|---|"
    )
    import tempfile

    from solas_mi.optics.pupil import chief_rays
    from solas_mi.psf.geometric import entrance_grid_hits
    from solas_mi.render.scene import write_scene
    from solas_mi.validation.scene_psf import scene_psf

    for rings in (16, 32, 64, 128):
        with tempfile.TemporaryDirectory() as tmp:
            scene = load_scene(
                write_scene(lens, tmp, "x.png", rings=rings, fresnel="off"),
                image=str(resource_dir("scenes") / "images" / "rocket.png"),
            )
            worst_c = worst_r = 0.0
            for field in ((0.0, 0.0), (0.0, 2.0), (0.0, -2.0)):
                for w in (486.0, 531.0, 656.0):
                    p = scene_psf(scene, lens, field, w, rays=512)
                    f, ww = np.array([field]), np.array([w])
                    dx, dy, pw = entrance_grid_hits(lens, f, ww, 512, chief_rays(lens, f, ww))[0]
                    cx, cy = np.average(dx, weights=pw), np.average(dy, weights=pw)
                    rms = math.sqrt(np.average((dx - cx) ** 2 + (dy - cy) ** 2, weights=pw))
                    worst_c = max(worst_c, math.hypot(p.meta["centroid_um"][0] - cx, p.meta["centroid_um"][1] - cy))
                    worst_r = max(worst_r, abs(p.meta["rms_radius_um"] / rms - 1))
        r = render_image(
            lens, image, sensor=(240, 320), pitch_um=camera.pitch_um, spp=64, response="lines", rings=rings
        )
        print(f"| {rings} | {worst_c:.3f} | {worst_r * 100:.3f} % | {r.samples_per_second / 1e6:.2f} |", flush=True)


if __name__ == "__main__":
    t = time.perf_counter()
    main()
    print(f"\n(total {time.perf_counter() - t:.0f} s)")
