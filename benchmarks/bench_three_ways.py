"""Samples per second of the three ways to render the lens, on the image scene and on a 3D scene
(2 cores, llvm_ad_spectral, median of `--repeats` after a warm-up):

- image scene (the bundled photograph at infinity, 320×240, the 531 nm line): solas-mi's loop on the
  lens as geometry, Mitsuba's `path` on the same scene, and `path` with `lens_camera`;
- 3D scene (a lit half-plane 100 m away, 320×240): `path` on the lens as geometry (cap meshes +
  `lens_sensor`, world in mm) and `path` with `lens_camera`.

    .venv/bin/python benchmarks/bench_three_ways.py [--repeats 3] [--spp 64]
"""

from __future__ import annotations

import argparse
import statistics
import time

import solas_mi
from solas_mi import Lens
from solas_mi.imageio import read_image, write_exr
from solas_mi.optics.camera import camera_for
from solas_mi.render.loop import render
from solas_mi.render.mitsuba import load_scene
from solas_mi.render.psf import lens_geometry
from solas_mi.render.scene import write_scene
from solas_mi.resources import resource_dir

BAND = {"type": "spectrum", "value": [(529.0, 0.0), (530.0, 1.0), (532.0, 1.0), (533.0, 0.0)]}
W, H = 320, 240


def timed(fn, repeats: int, samples: int) -> tuple[float, list[float]]:
    fn()  # warm-up: kernels compile
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return samples / statistics.median(times) / 1e6, times


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--spp", type=int, default=64)
    args = ap.parse_args()
    mi = solas_mi.mitsuba("llvm_ad_spectral")
    lens = Lens.load("solas-doublet")
    samples = W * H * args.spp
    film = {"type": "specfilm", "width": W, "height": H, "rfilter": {"type": "box"}, "Y": BAND}
    back = mi.ScalarTransform4f().look_at(origin=[0, 0, 0], target=[0, 0, -1], up=[0, 1, 0])
    import tempfile
    from pathlib import Path

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        image = read_image(resource_dir("scenes") / "images" / "rocket.png")[::4, ::4].mean(axis=-1)
        write_exr(Path(tmp) / "image.exr", {"Y": image})
        cam = camera_for(lens, (H, W))
        xml = write_scene(lens, tmp, str(Path(tmp) / "image.exr"), cam, response="mono:531", fresnel="off")
        geo = load_scene(xml, "llvm_ad_spectral")
        rows.append(
            ("image", "solas-mi loop, lens as geometry", *timed(lambda: render(geo, args.spp), args.repeats, samples))
        )
        text = xml.read_text()
        start, end = text.index('<film type="hdrfilm">'), text.index("</film>") + len("</film>")
        xml.write_text(
            text[:start] + '<film type="specfilm"><integer name="width" value="$width"/><integer '
            'name="height" value="$height"/><rfilter type="box"/><spectrum name="Y" '
            'value="529:0, 530:1, 532:1, 533:0"/></film>' + text[end:]
        )
        stock = load_scene(xml, "llvm_ad_spectral")
        rows.append(
            (
                "image",
                "Mitsuba path, lens as geometry",
                *timed(lambda: mi.render(stock, spp=args.spp), args.repeats, samples),
            )
        )
        camera = mi.load_dict(
            {
                "type": "scene",
                "integrator": {"type": "path", "max_depth": 2},
                "sensor": {
                    "type": "lens_camera",
                    "pitch_um": cam.pitch_um,
                    "response": "mono:531",
                    "to_world": back,
                    "film": film,
                },
                "object": {"type": "image_object", "filename": str(Path(tmp) / "image.exr"), "fov_deg": cam.fov_deg},
            }
        )
        rows.append(
            (
                "image",
                "Mitsuba path, lens_camera",
                *timed(lambda: mi.render(camera, spp=args.spp), args.repeats, samples),
            )
        )

    def plane():
        tf = mi.ScalarTransform4f().translate([1e5, 0, -1e5]).scale(1e5)
        return {
            "type": "rectangle",
            "to_world": tf,
            "emitter": {"type": "area", "radiance": {"type": "uniform", "value": 1.0}},
        }

    geometry = lens_geometry(
        lens,
        integrator={"type": "path", "max_depth": 8},
        edge=plane(),
        sensor={"type": "lens_sensor", "lens": lens.source, "pitch_um": 2.0, "response": "mono:531", "film": film},
    )
    sequential = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 2},
            "edge": plane(),
            "sensor": {
                "type": "lens_camera",
                "lens": lens.source,
                "pitch_um": 2.0,
                "response": "mono:531",
                "world_unit_mm": 1.0,
                "film": film,
                "to_world": back,
            },
        }
    )
    rows.append(
        (
            "3D",
            "Mitsuba path, lens as geometry",
            *timed(lambda: mi.render(geometry, spp=args.spp), args.repeats, samples),
        )
    )
    rows.append(
        ("3D", "Mitsuba path, lens_camera", *timed(lambda: mi.render(sequential, spp=args.spp), args.repeats, samples))
    )
    print("| scene | renderer | M samples/s | runs (s) |\n|---|---|---|---|")
    for scene, name, rate, times in rows:
        print(f"| {scene} | {name} | {rate:.2f} | {', '.join(f'{t:.2f}' for t in times)} |")


if __name__ == "__main__":
    main()
