"""RGB noise against time: `lens_camera` against Mitsuba's `perspective` camera on three small scenes.

Run: .venv/bin/python benchmarks/bench_lens_camera_noise.py [--repeats 3] [--spp 4,8,16,32] [--size 128x96]
     [--independent-wavelengths] [--lane-tolerance EPS]
Scenes (written here, world in metres, srgb camera, hdrfilm, `independent` sampler):
- room: a diffuse box (red and green side walls, white floor, ceiling and back) lit by a ceiling
  light, two diffuse blocks inside (`path`, depth 6);
- env: three spheres (diffuse, rough plastic, rough gold) on a grey floor under a coloured
  environment map written here (`path`, depth 6);
- glass: a glass sphere (`dielectric`) and a box of scattering medium (`homogeneous`, coloured
  albedo) in the room (`volpath`, depth 12).
Cameras: `lens_camera` (double_gauss_50mm, pitch giving a 24 × 18 mm film at the default size,
focused at the scene) and `perspective` with the lens's horizontal field, the same pose. For each
camera and scene: a reference at 32 × the largest spp, then renders at each spp (`repeats` seeds):
relative RGB noise = RMS(render − reference) / RMS(reference) over all pixels and channels (median
over seeds), and wall-clock seconds of `mi.render` (median, kernels compiled by a warm-up). Both
cameras run in the same process, their renders interleaved (each seed renders both in turn: a change
in the machine's load reaches both alike). The time to equal noise, with noise ∝
(time)^(−1/2) at the largest spp: lens seconds × (lens noise / perspective noise)² / perspective
seconds. `--independent-wavelengths` switches the lens
camera's per-pixel stratification of wavelengths off for comparison; `--lane-tolerance` sets its
`lane_tolerance` (0: no path shared among the spectral lanes; default: the plugin's).
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path
from statistics import median

import numpy as np

from solas_mi import Lens

LENS = "double_gauss_50mm"
FILM_WIDTH_MM = 24.0


def _rect(mi, to_world, bsdf):
    return {"type": "rectangle", "to_world": to_world, "bsdf": bsdf}


def _diffuse(rgb):
    return {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(rgb)}}


def _room(mi) -> dict:
    """A 2 m box around z ∈ [1, 3], open toward the camera at the origin (looking along +z)."""
    T = mi.ScalarTransform4f
    white, red, green = _diffuse((0.75, 0.75, 0.75)), _diffuse((0.7, 0.1, 0.1)), _diffuse((0.1, 0.6, 0.15))
    return {
        "floor": _rect(mi, T().translate([0, -1, 2]).rotate([1, 0, 0], -90), white),
        "ceiling": _rect(mi, T().translate([0, 1, 2]).rotate([1, 0, 0], 90), white),
        "back": _rect(mi, T().translate([0, 0, 3]).rotate([0, 1, 0], 180), white),
        "left": _rect(mi, T().translate([1, 0, 2]).rotate([0, 1, 0], -90), red),
        "right": _rect(mi, T().translate([-1, 0, 2]).rotate([0, 1, 0], 90), green),
        "light": {
            "type": "rectangle",
            "to_world": T().translate([0, 0.99, 2]).rotate([1, 0, 0], 90).scale(0.3),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [12.0, 11.0, 9.0]}},
        },
    }


def _env_map(path: Path) -> str:
    from solas_mi.imageio import image_channels, write_exr

    v, u = np.mgrid[0:64, 0:128] / np.array([64.0, 128.0])[:, None, None]
    sky = np.stack([0.4 + 0.6 * u, 0.5 + 0.4 * (1 - v), 1.2 - 0.8 * v], axis=-1).astype(np.float32)
    sky[20:26, 40:52] = (8.0, 6.0, 3.0)  # a sun
    write_exr(str(path), image_channels(sky))
    return str(path)


def scene_dict(mi, name: str, sensor: dict, folder: Path) -> dict:
    T = mi.ScalarTransform4f
    scene = {"type": "scene", "sensor": sensor}
    if name == "room":
        scene.update(
            _room(mi),
            integrator={"type": "path", "max_depth": 6},
            block={
                "type": "cube",
                "to_world": T().translate([0.4, -0.6, 2.2]).scale(0.4),
                "bsdf": _diffuse((0.6, 0.6, 0.3)),
            },
        )
    elif name == "env":
        scene.update(
            integrator={"type": "path", "max_depth": 6},
            sky={"type": "envmap", "filename": _env_map(folder / "sky.exr")},
            floor=_rect(mi, T().translate([0, -0.5, 2]).rotate([1, 0, 0], -90).scale(3), _diffuse((0.4, 0.4, 0.4))),
            a={"type": "sphere", "center": [-0.6, -0.2, 2.0], "radius": 0.3, "bsdf": _diffuse((0.2, 0.5, 0.8))},
            b={
                "type": "sphere",
                "center": [0.0, -0.2, 2.2],
                "radius": 0.3,
                "bsdf": {
                    "type": "roughplastic",
                    "alpha": 0.1,
                    "diffuse_reflectance": {"type": "rgb", "value": [0.8, 0.2, 0.1]},
                },
            },
            c={
                "type": "sphere",
                "center": [0.6, -0.2, 2.0],
                "radius": 0.3,
                "bsdf": {"type": "roughconductor", "material": "Au", "alpha": 0.15},
            },
        )
    else:
        scene.update(
            _room(mi),
            integrator={"type": "volpath", "max_depth": 12},
            ball={
                "type": "sphere",
                "center": [-0.35, -0.5, 2.0],
                "radius": 0.4,
                "bsdf": {"type": "dielectric", "int_ior": "bk7"},
            },
            fog={
                "type": "cube",
                "to_world": T().translate([0.45, -0.6, 2.3]).scale(0.35),
                "bsdf": {"type": "null"},
                "interior": {
                    "type": "homogeneous",
                    "sigma_t": 4.0,
                    "albedo": {"type": "rgb", "value": [0.9, 0.6, 0.3]},
                },
            },
        )
    return scene


def cameras(mi, lens: Lens, width: int, height: int, independent: bool, lane_tolerance: float | None = None) -> dict:
    from solas_mi.optics.paraxial import paraxial

    pitch_um = FILM_WIDTH_MM / width * 1e3
    fov = 2 * math.degrees(math.atan(0.5 * FILM_WIDTH_MM / paraxial(lens).efl_mm))
    film = {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"}}
    sampler = {"type": "independent", "sample_count": 4}
    lens_camera = {
        "type": "lens_camera",
        "lens": LENS,
        "pitch_um": pitch_um,
        "response": "srgb",
        "focus_distance": 2.0,
        "film": film,
        "sampler": sampler,
    }
    if independent:
        lens_camera["stratify_wavelengths"] = False
    if lane_tolerance is not None:
        lens_camera["lane_tolerance"] = lane_tolerance
    return {
        "lens_camera": lens_camera,
        "perspective": {"type": "perspective", "fov": fov, "fov_axis": "x", "film": film, "sampler": sampler},
    }


def noise(image: np.ndarray, reference: np.ndarray) -> float:
    return float(np.sqrt(np.mean((image - reference) ** 2)) / np.sqrt(np.mean(reference**2)))


def measure(mi, scenes: dict, spps, repeats: int) -> dict:
    """Per camera: (spp, median relative noise, median seconds) per spp, against a reference at 32 × max
    spp; the cameras' renders interleaved (each seed renders every camera in turn), so that a change
    in the machine's load reaches both alike."""
    references = {
        cam: np.mean([np.array(mi.render(scene, spp=4 * max(spps), seed=1000 + s)) for s in range(8)], axis=0)
        for cam, scene in scenes.items()
    }
    rows = {cam: [] for cam in scenes}
    for spp in spps:
        noises, seconds = {cam: [] for cam in scenes}, {cam: [] for cam in scenes}
        for r in range(repeats):
            for cam, scene in scenes.items():
                start = time.perf_counter()
                image = np.array(mi.render(scene, spp=spp, seed=r + 1))
                seconds[cam].append(time.perf_counter() - start)
                noises[cam].append(noise(image, references[cam]))
        for cam in scenes:
            rows[cam].append((spp, median(noises[cam]), median(seconds[cam])))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--spp", default="4,8,16,32")
    parser.add_argument("--size", default="128x96")
    parser.add_argument("--scenes", default="room,env,glass")
    parser.add_argument("--independent-wavelengths", action="store_true")
    parser.add_argument("--lane-tolerance", type=float, default=None)
    args = parser.parse_args()
    import solas_mi

    mi = solas_mi.mitsuba("llvm_ad_spectral")
    width, height = (int(v) for v in args.size.split("x"))
    spps = [int(v) for v in args.spp.split(",")]
    lens = Lens.load(LENS)
    folder = Path(tempfile.mkdtemp())
    print(f"| scene | camera | {' | '.join(f'{s} spp noise / s' for s in spps)} | time to equal noise |")
    print(f"|---|---|{'---|' * len(spps)}---|")
    for name in args.scenes.split(","):
        scenes = {
            cam: mi.load_dict(scene_dict(mi, name, sensor, folder))
            for cam, sensor in cameras(
                mi, lens, width, height, args.independent_wavelengths, args.lane_tolerance
            ).items()
        }
        for scene in scenes.values():
            mi.render(scene, spp=spps[0], seed=0)  # warm-up: kernels compiled
        results = measure(mi, scenes, spps, args.repeats)
        (_, n_lens, t_lens), (_, n_persp, t_persp) = results["lens_camera"][-1], results["perspective"][-1]
        ratio = t_lens * (n_lens / n_persp) ** 2 / t_persp
        for cam, rows in results.items():
            cells = " | ".join(f"{n * 100:.1f} % / {t:.2f}" for _, n, t in rows)
            print(f"| {name} | {cam} | {cells} | {f'{ratio:.2f}×' if cam == 'lens_camera' else '1'} |", flush=True)


if __name__ == "__main__":
    main()
