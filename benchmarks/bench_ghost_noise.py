"""The lens camera's ghosts: their noise at the direct image's spp, and the render time with ghosts.

Run: .venv/bin/python benchmarks/bench_ghost_noise.py [--spp 64] [--size 128x96] [--variant llvm_ad_spectral]

Scenes (the double Gauss, bare glass, `path` depth 1, a dim uniform sky of radiance 1e-4 and area emitters
of radiance 1, far ones as spheres 10 km away):
- sun: a sun (0.27° radius) at 8° off axis;
- near-sun: a disc of 1° radius at 3°;
- headlights: two discs of 0.1 m radius 20 m ahead, 1.5 m apart, 1 m below the axis.
For each scene: the stray light alone (`ghosts` "only") at `spp`, three seeds, with the pupil points guided
toward the emitters (`ghost_guide`) and uniform on the square (the guide left out); the relative noise per
pixel inside the strongest ghost (the brightest tenth of the stray light, chosen from the third seed's
guided render): the RMS of the two other seeds' difference over √2, over their mean there; against the
relative noise of the direct image (ghosts off) of the uniform sky alone at the same spp, in the film's
central quarter. Times: `mi.render` wall seconds of the direct image (ghosts off) and of the stray light
(guided, its guide built in the first render), each after a warm-up render; `render --ghosts` renders both.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

LENS = "double-gauss-50mm"
FAR = 1e4  # m


def sphere_at(field_deg: tuple[float, float], radius_deg: float) -> dict:
    """A far sphere emitter at field (x, y) degrees (the lens frame; the camera's is (x, −y, −z))."""
    tx, ty = (math.tan(math.radians(f)) for f in field_deg)
    return {
        "type": "sphere",
        "center": [-tx * FAR, ty * FAR, FAR],
        "radius": FAR * math.hypot(1.0, tx, ty) * math.radians(radius_deg),
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 1.0}},
    }


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
    "sun": lambda: {"sun": sphere_at((0.0, 8.0), 0.27)},
    "near-sun": lambda: {"sun": sphere_at((2.0, 2.0), 1.0)},
    "headlights": lambda: {"left": disc_at(-0.75, -1.0, 20.0, 0.1), "right": disc_at(0.75, -1.0, 20.0, 0.1)},
}


def scene(mi, shapes: dict, ghosts: str, size: tuple[int, int], spp: int, sky: float = 1e-4):
    sensor = {
        "type": "lens_camera",
        "lens": LENS,
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


def render(mi, sc, spp: int, seed: int) -> tuple[np.ndarray, float]:
    start = time.perf_counter()
    image = np.array(mi.render(sc, spp=spp, seed=seed), dtype=np.float64).mean(axis=-1)
    return image, time.perf_counter() - start


def noise(a: np.ndarray, b: np.ndarray, region) -> float:
    return float(np.sqrt(np.mean((a[region] - b[region]) ** 2 / 2.0)) / (0.5 * (a[region] + b[region])).mean())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--size", default="128x96")
    parser.add_argument("--variant", default="llvm_ad_spectral")
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    from solas_mi.render.mitsuba import mitsuba

    mi = mitsuba(args.variant)
    sky = scene(mi, {}, "off", size, args.spp, sky=1.0)
    centre = np.zeros(size[::-1], bool)
    centre[size[1] // 4 : 3 * size[1] // 4, size[0] // 4 : 3 * size[0] // 4] = True
    patch = noise(render(mi, sky, args.spp, 0)[0], render(mi, sky, args.spp, 1)[0], centre)
    print(f"direct image of a uniform sky, {args.spp} spp: relative noise {patch:.4f}")
    print(
        "| scene | guided noise | uniform noise | guided / sky patch | direct s | stray s (guide built) | stray s | with / without |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name, shapes in SCENES.items():
        direct = scene(mi, shapes(), "off", size, args.spp)
        render(mi, direct, args.spp, 9)  # warm-up
        t_direct = render(mi, direct, args.spp, 8)[1]
        guided = scene(mi, shapes(), "only", size, args.spp)
        first, t_build = render(mi, guided, args.spp, 2)
        (a, t_stray), (b, _) = render(mi, guided, args.spp, 0), render(mi, guided, args.spp, 1)
        region = first >= np.quantile(first[first > 0], 0.9)
        plain = scene(mi, shapes(), "only", size, args.spp)
        plain.sensors()[0].ghosts.aim = lambda *args: None
        ua, ub = render(mi, plain, args.spp, 0)[0], render(mi, plain, args.spp, 1)[0]
        g, u = noise(a, b, region), noise(ua, ub, region)
        print(
            f"| {name} | {g:.3f} | {u:.3f} | {g / patch:.1f} | {t_direct:.2f} | {t_build:.2f} | {t_stray:.2f} | "
            f"{(t_direct + t_stray) / t_direct:.2f} |"
        )


if __name__ == "__main__":
    main()
