"""The ghosts of `render --ghosts`: their noise at the direct image's spp, and the render time with ghosts.

Run: .venv/bin/python benchmarks/bench_ghost_noise.py [--spp 64] [--size 128x96] [--variant llvm_ad_spectral]
     [--path-sampled]

Scenes (the double Gauss, bare glass, `path` depth 1, a dim uniform sky of radiance 1e-4):
- sun: a `directional` sun of irradiance 1 at 8° off axis;
- near-sun: a far sphere emitter of radiance 1, 1° radius, at (2°, 2°);
- headlights: two discs of radiance 1 and 0.1 m radius 20 m ahead, 1.5 m apart, 1 m below the axis.
For each scene: the stray light alone traced from the sources (`render.ghost_light.stray_light`, what
`render --ghosts` adds) at `spp`, three seeds; the relative noise per pixel inside the strongest ghost (the
brightest tenth of the stray light, chosen from the third seed's image): the RMS of the two other seeds'
difference over √2, over their mean there; against the relative noise of the direct image (ghosts off) of
the uniform sky alone at the same spp, in the film's central quarter. With --path-sampled, also the lens
camera's own path sampling (`ghosts` "only", guided toward area emitters) at the same spp, for comparison.
Times, paired (direct, stray, direct, stray, …, after a warm-up of each: the kernels compiled): wall and
process CPU seconds of the direct image (`mi.render`, ghosts off) and of the stray light; the machine's
load average is printed.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time

import numpy as np

LENS = "double-gauss-50mm"  # with its coatings removed (`bare_lens`): bare glass, whatever the shipped file says
FAR = 1e4  # m


def bare_lens(folder: str) -> str:
    """`LENS` without coatings, written to a lens file in `folder`: its path."""
    import dataclasses
    from pathlib import Path

    from solas_mi import Lens

    lens = Lens.load(LENS)
    bare = dataclasses.replace(lens, surfaces=tuple(dataclasses.replace(s, coating=None) for s in lens.surfaces))
    return str(bare.save(Path(folder) / "double-gauss-bare.toml"))


def sphere_at(field_deg: tuple[float, float], radius_deg: float) -> dict:
    """A far sphere emitter at field (x, y) degrees (the lens frame; the camera's is (x, −y, −z))."""
    tx, ty = (math.tan(math.radians(f)) for f in field_deg)
    return {
        "type": "sphere",
        "center": [-tx * FAR, ty * FAR, FAR],
        "radius": FAR * math.hypot(1.0, tx, ty) * math.radians(radius_deg),
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 1.0}},
    }


def directional_at(field_deg: tuple[float, float]) -> dict:
    """A directional emitter of irradiance 1 whose light comes from field (x, y) degrees (lens frame)."""
    tx, ty = (math.tan(math.radians(f)) for f in field_deg)
    toward = np.array([-tx, ty, 1.0]) / math.hypot(1.0, tx, ty)  # toward the sun, camera frame
    return {"type": "directional", "direction": (-toward).tolist(), "irradiance": {"type": "rgb", "value": 1.0}}


def disc_at(x: float, y: float, z: float, radius: float) -> dict:
    """A disc emitter facing the camera at (x, y, z) m of the camera frame."""
    import mitsuba as mi

    to_world = mi.ScalarTransform4f().translate([x, y, z]).scale(radius).rotate([1, 0, 0], 180.0)
    return {
        "type": "disk",
        "to_world": to_world,
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 1.0}},
    }


SCENES = {
    "sun": lambda: {"sun": directional_at((0.0, 8.0))},
    "near-sun": lambda: {"sun": sphere_at((2.0, 2.0), 1.0)},
    "headlights": lambda: {"left": disc_at(-0.75, -1.0, 20.0, 0.1), "right": disc_at(0.75, -1.0, 20.0, 0.1)},
}


def scene(mi, shapes: dict, ghosts: str, size: tuple[int, int], spp: int, sky: float = 1e-4, lens: str = LENS):
    sensor = {
        "type": "lens_camera",
        "lens": lens,
        "fresnel": "transmit",
        "film": {"type": "hdrfilm", "width": size[0], "height": size[1], "rfilter": {"type": "box"}},
        "sampler": {"type": "independent", "sample_count": spp},
    }
    if ghosts != "off":
        sensor["ghosts"] = ghosts
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 1},
            "sensor": sensor,
            "sky": {"type": "constant", "radiance": {"type": "rgb", "value": sky}},
            **shapes,
        }
    )


def render(mi, sc, spp: int, seed: int) -> tuple[np.ndarray, float, float]:
    """The direct image (channel mean) of `sc` and its wall and CPU seconds."""
    wall, cpu = time.perf_counter(), time.process_time()
    image = np.array(mi.render(sc, spp=spp, seed=seed), dtype=np.float64)[..., :3].mean(axis=-1)
    return image, time.perf_counter() - wall, time.process_time() - cpu


def traced(sc, spp: int, seed: int) -> tuple[np.ndarray, float, float]:
    """The light-traced stray light (channel mean) of `sc` and its wall and CPU seconds."""
    from solas_mi.render.ghost_light import stray_light

    wall, cpu = time.perf_counter(), time.process_time()
    image = stray_light(sc, sc.sensors()[0], spp, seed)[0].mean(axis=-1)
    return image, time.perf_counter() - wall, time.process_time() - cpu


def noise(a: np.ndarray, b: np.ndarray, region) -> float:
    return float(np.sqrt(np.mean((a[region] - b[region]) ** 2 / 2.0)) / (0.5 * (a[region] + b[region])).mean())


def measure(mi, name: str, lens: str, size, spp: int, patch: float, path_sampled: bool, pairs: int = 3) -> str:
    """One scene's row of the table (module docstring) through the lens file `lens`."""
    direct = scene(mi, SCENES[name](), "off", size, spp, lens=lens)
    render(mi, direct, spp, 9)  # warm-up: kernels compiled
    first = traced(direct, spp, 2)[0]
    times = np.array([[*render(mi, direct, spp, 8 + k)[1:], *traced(direct, spp, 10 + k)[1:]] for k in range(pairs)])
    a, b = traced(direct, spp, 0)[0], traced(direct, spp, 1)[0]
    region = first >= np.quantile(first[first > 0], 0.9)
    light = noise(a, b, region)
    sampled = "—"
    if path_sampled:
        only = scene(mi, SCENES[name](), "only", size, spp, lens=lens)
        sampled = f"{noise(render(mi, only, spp, 0)[0], render(mi, only, spp, 1)[0], region):.3f}"
    t = np.median(times, axis=0)
    return (
        f"| {name} | {light:.3f} | {light / patch:.2f} | {sampled} | {t[0]:.2f} / {t[1]:.2f} | {t[2]:.2f} / {t[3]:.2f} | "
        f"{(t[0] + t[2]) / t[0]:.2f} / {(t[1] + t[3]) / t[1]:.2f} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--size", default="128x96")
    parser.add_argument("--variant", default="llvm_ad_spectral")
    parser.add_argument("--path-sampled", action="store_true", help="also the lens camera's own ghost sampling")
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    from solas_mi.render.mitsuba import mitsuba

    mi = mitsuba(args.variant)
    folder = tempfile.mkdtemp()
    lens = bare_lens(folder)
    sky = scene(mi, {}, "off", size, args.spp, sky=1.0, lens=lens)
    centre = np.zeros(size[::-1], bool)
    centre[size[1] // 4 : 3 * size[1] // 4, size[0] // 4 : 3 * size[0] // 4] = True
    patch = noise(render(mi, sky, args.spp, 0)[0], render(mi, sky, args.spp, 1)[0], centre)
    print(f"direct image of a uniform sky, {args.spp} spp, {size[0]}x{size[1]}: relative noise {patch:.4f}")
    print(f"load average at the start: {os.getloadavg()}")
    print(
        "| scene | light-traced noise | / sky patch | path-sampled noise | direct s (wall / CPU) | "
        "stray s (wall / CPU) | with / without (wall / CPU) |"
    )
    print("|---|---|---|---|---|---|---|")
    for name in SCENES:
        print(measure(mi, name, lens, size, args.spp, patch, args.path_sampled), flush=True)
    print(f"load average at the end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
