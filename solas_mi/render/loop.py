"""Direct spectral rendering through the lens geometry: Mitsuba set-up (variant, plugins), the path
loop, and rendering an input image or a scene file.

The loop follows camera paths from the `lens_sensor` through the glass (`sellmeier_dielectric`)
until they leave the lens; a path that escapes toward the object takes the `image_object`'s
radiance. One wavelength per path; each sample adds response_c(λ)/p(λ) × its radiance to the
channels of its pixel (a box pixel: the mean irradiance over the pixel's area).
"""
from __future__ import annotations

import importlib
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import SolasError
from ..llvm import select_libllvm

VARIANTS = ("llvm_ad_spectral", "scalar_spectral", "cuda_ad_spectral")
_PLUGINS = ("sellmeier_dielectric", "image_object", "lens_sensor")
_SAMPLES_PER_PASS = 1 << 22  # samples traced at once: bounds the memory of one pass


def default_variant() -> str:
    """cuda_ad_spectral where a CUDA device works, else llvm_ad_spectral."""
    select_libllvm()
    import drjit as dr

    return "cuda_ad_spectral" if dr.has_backend(dr.JitBackend.CUDA) else "llvm_ad_spectral"


def mitsuba(variant: str | None = None):
    """Mitsuba with `variant` set (default: `default_variant`) and the solas-mi plugins registered."""
    variant = variant or default_variant()
    if variant not in VARIANTS:
        raise SolasError(f"variant {variant!r} must be one of {', '.join(VARIANTS)}")
    select_libllvm()
    import mitsuba as mi

    if variant not in mi.variants():
        raise SolasError(f"variant {variant} is not in this Mitsuba build (has: {', '.join(mi.variants())})")
    if mi.variant() != variant:
        try:
            mi.set_variant(variant)
        except Exception as exc:  # a CUDA variant without a working device
            raise SolasError(f"Mitsuba variant {variant} cannot start: {exc}") from exc
        for name in _PLUGINS:  # the plugin classes subclass the current variant's types
            module = importlib.import_module(f"solas_mi.plugins.{name}")
            importlib.reload(module).register()
    return mi


@dataclass
class Render:
    """A rendered image (H×W×C, float32, image orientation) and what produced it."""

    image: np.ndarray
    channels: tuple[str, ...]
    spp: int
    seconds: float
    samples_per_second: float
    meta: dict = field(default_factory=dict)

    def write(self, path: str, png: str | None = None) -> str:
        """OpenEXR (linear, one channel per response channel, metadata in the header) and an sRGB PNG
        beside it (or at `png`); returns the PNG's path."""
        from ..imageio import write_exr, write_png

        meta = dict(self.meta, spp=self.spp, samples_per_second=self.samples_per_second)
        write_exr(path, {c: self.image[..., k] for k, c in enumerate(self.channels)}, meta)
        png = png or str(Path(path).with_suffix(".png"))
        write_png(png, self.image[..., 0] if self.image.shape[-1] == 1 else self.image)
        return png


def _components(scene):
    sensor, emitters = scene.sensors()[0], scene.emitters()
    if type(sensor).__name__ != "LensSensor":
        raise SolasError(f"the scene's sensor is {type(sensor).__name__}; solas-mi renders need a lens_sensor")
    objects = [e for e in emitters if type(e).__name__ == "ImageObject"]
    if len(objects) != 1:
        raise SolasError(f"the scene needs exactly one image_object emitter (has {len(objects)})")
    return sensor, objects[0]


SPAWN_OFFSET_MM = 1e-4  # a continued ray starts this far along its own direction


def continue_ray(si, ray, wo_local):
    """The ray leaving interaction `si` in local direction `wo_local`, started a hair along itself.
    (Mitsuba's spawn_ray offsets along the normal by ~1e-4 of the scene scale, up to ~10 µm here,
    which shifts refracted rays sideways.)"""
    import mitsuba as mi

    d = si.to_world(wo_local)
    return mi.Ray3f(si.p + d * SPAWN_OFFSET_MM, d, ray.time, ray.wavelengths)


def _max_depth(scene, lens) -> int:
    """Interactions a path needs: one per refracting surface and the escape; with sampled Fresnel
    reflections, room for a ghost (two reflections and the way back)."""
    refracting = sum(1 for k, s in enumerate(lens.surfaces)
                     if s.glass != (lens.surfaces[k - 1].glass if k else lens.object_glass))
    ghosts = any(getattr(shape.bsdf(), "fresnel", None) == "sample" for shape in scene.shapes())
    return 3 * refracting + 2 if ghosts else refracting + 2


def render(scene, spp: int, seed: int = 0, max_depth: int | None = None, progress=None) -> Render:
    """Render a lens scene with `spp` samples per pixel in passes of bounded size."""
    import drjit as dr
    import mitsuba as mi

    if not (isinstance(spp, int) and spp >= 1):
        raise SolasError(f"samples per pixel {spp!r} must be a positive integer")
    sensor, emitter = _components(scene)
    if spp < max(sensor.discrete_lines, 1):
        raise SolasError(f"samples per pixel {spp} must be at least the response's {sensor.discrete_lines} lines "
                         "(each line needs its own samples)")
    width, height, nc = sensor.width, sensor.height, sensor.channels
    depth = max_depth if max_depth is not None else _max_depth(scene, sensor.lens)
    pixels = width * height
    per_pass = max(1, min(spp, _SAMPLES_PER_PASS // pixels))
    passes = math.ceil(spp / per_pass)
    accum = np.zeros(pixels * nc, dtype=np.float64)
    start, cpu = time.perf_counter(), time.process_time()
    done = 0
    for k in range(passes):
        n_spp = min(per_pass, spp - done)
        run = _pass if dr.is_jit_v(mi.Float) else _pass_scalar
        accum += run(mi, dr, scene, sensor, emitter, n_spp, done, spp, seed, seed * 1_000_003 + k + 1, depth)
        done += n_spp
        if progress is not None:
            progress(done, spp)
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    image = (accum / spp).reshape(height, width, nc).astype(np.float32)
    return Render(image, tuple(sensor.response.channels), spp, seconds, pixels * spp / seconds,
                  {"variant": mi.variant(), "spp": spp, "max_depth": depth, "seconds": seconds, "cpu_seconds": cpu,
                   **sensor.response.meta()})


def _line_shares(total: int, lines: int) -> list[float]:
    """Weight of a sample of each spectral line when sample s of `total` takes line s % lines: the
    response's weights assume 1/lines of the samples per line, the count may differ by one."""
    return [total / (lines * len(range(c, total, lines))) for c in range(lines)]


def _pass(mi, dr, scene, sensor, emitter, spp: int, first: int, total: int, base: int, seed: int, depth: int
          ) -> np.ndarray:
    """Samples first…first+spp−1 of every pixel's stratified set of `total`, traced as one wavefront;
    returns the per-pixel, per-channel sums."""
    from .sampling import cmj_2d, hash_seed, stratified_1d

    width, height, nc = sensor.width, sensor.height, sensor.channels
    n = width * height * spp
    total_samples = total

    sampler = mi.load_dict({"type": "independent", "sample_count": spp})
    sampler.seed(seed, n)
    idx = dr.arange(mi.UInt32, n)
    pixel = idx // spp
    s = idx % spp + first  # the sample's index in its pixel's stratified set of `total`
    lines = sensor.discrete_lines
    if lines:  # each line gets its own stratified set, so every channel sees a stratified pupil
        band = s % lines
        s, total = s // lines, -(-total // lines)
        s1 = (mi.Float(band) + 0.5) / lines
        share = dr.gather(mi.Float, mi.Float(_line_shares(total_samples, lines)), band)
    else:
        s1 = stratified_1d(s, total, hash_seed(pixel, 2, base), sampler.next_1d())
        share = mi.Float(1.0)
    film = mi.Point2f(mi.Float(pixel % width), mi.Float(pixel // width))
    # a pixel that covers at most two texels is integrated exactly by the object's footprint filter
    filtered = sensor.max_footprint <= 2.0 * emitter.tan_pitch
    jitter = mi.Point2f(0.5) if filtered else cmj_2d(s, total, hash_seed(pixel, 1, base), sampler.next_2d())
    pos = (film + jitter) / mi.ScalarPoint2f(width, height)
    footprint = sensor.footprint(sensor.film_point(pos)) if filtered else None
    aperture = cmj_2d(s, total, hash_seed(pixel, 3, base), sampler.next_2d())
    ray, throughput = sensor.sample_ray(0.0, s1, pos, aperture)
    _, band = sensor.sample_wavelength(s1)
    ctx = mi.BSDFContext()
    radiance = mi.Float(0.0)
    weight = throughput[0] * share
    active = mi.Bool(True)
    for _ in range(depth):
        si = scene.ray_intersect(ray, active)
        escaped = active & ~si.is_valid()
        radiance += dr.select(escaped, weight * emitter.radiance(ray.o, ray.d, ray.wavelengths, escaped,
                                                                             footprint)[0], 0.0)
        active &= si.is_valid()
        bs, bw = si.bsdf(ray).sample(ctx, si, sampler.next_1d(active), sampler.next_2d(active), active)
        weight *= bw[0]
        active &= weight != 0.0
        ray = continue_ray(si, ray, bs.wo)
    out = dr.zeros(mi.Float, width * height * nc)
    for c, w in enumerate(sensor.channel_weights(band)):
        dr.scatter_reduce(dr.ReduceOp.Add, out, radiance * w, pixel * nc + c)
    dr.eval(out)
    return np.asarray(out, dtype=np.float64) * 1.0  # the pass's sum over its samples


def load_scene(path: str, variant: str | None = None, **params):
    """Load a scene XML with the solas-mi plugins; `params` fill its <default> values."""
    mi = mitsuba(variant)
    try:
        return mi.load_file(str(path), **{k: str(v) for k, v in params.items()})
    except RuntimeError as exc:
        raise SolasError(f"cannot load scene {path}: {exc}") from None


def render_image(lens, image: str | np.ndarray, sensor: tuple[int, int] = (960, 1280), pitch_um: float | None = None,
                 spp: int = 64, response: str = "srgb", fov_deg: float | None = None, boundary: str = "edge",
                 fresnel: str = "transmit", rings: int | None = None, variant: str | None = None, seed: int = 0,
                 progress=None) -> Render:
    """Render an input image (a path, or a linear H×W[×3] array) through `lens` onto a sensor of
    (rows, columns) pixels. Defaults: the image width spans ±lens.field_deg and the sensor's width
    spans the same field (`solas_mi.camera`)."""
    import tempfile

    from ..optics.camera import camera_for
    from .scene import DEFAULT_RINGS, write_scene

    camera = camera_for(lens, sensor, fov_deg, pitch_um)
    with tempfile.TemporaryDirectory(prefix="solas-scene-") as tmp:
        if isinstance(image, np.ndarray):
            from ..imageio import image_channels, write_exr

            path = str(Path(tmp) / "object.exr")
            write_exr(path, image_channels(np.asarray(image, dtype=np.float32)))
            image = path
        xml = write_scene(lens, tmp, str(Path(image).resolve()), camera, rings or DEFAULT_RINGS, spp, response,
                          boundary, fresnel)
        scene = load_scene(xml, variant)
        result = render(scene, spp, seed=seed, progress=progress)
    result.meta.update(camera.meta())
    result.meta.update({"lens": lens.name, "lens_hash": lens.hash, "boundary": boundary, "fresnel": fresnel,
                        "cap_rings": rings or DEFAULT_RINGS})
    return result


def _pass_scalar(mi, dr, scene, sensor, emitter, spp: int, first: int, total: int, base: int, seed: int, depth: int
                 ) -> np.ndarray:
    """`_pass` one sample at a time, for the scalar reference variants: the same estimator with
    independent samples (no stratification), each line of a discrete response sampled equally often."""
    width, height, nc = sensor.width, sensor.height, sensor.channels
    rng = np.random.default_rng([base, seed])
    out = np.zeros(width * height * nc)
    lines = sensor.discrete_lines
    shares = _line_shares(total, lines) if lines else []
    filtered = sensor.max_footprint <= 2.0 * emitter.tan_pitch
    ctx = mi.BSDFContext()
    for pixel in range(width * height):
        for k in range(spp):
            s = first + k
            u = rng.random(8)
            s1 = (s % lines + 0.5) / lines if lines else u[0]
            share = shares[s % lines] if lines else 1.0
            jitter = (0.5, 0.5) if filtered else (u[1], u[2])
            pos = mi.Point2f((pixel % width + jitter[0]) / width, (pixel // width + jitter[1]) / height)
            footprint = sensor.footprint(sensor.film_point(pos)) if filtered else None
            ray, throughput = sensor.sample_ray(0.0, s1, pos, mi.Point2f(u[3], u[4]))
            _, band = sensor.sample_wavelength(s1)
            weight, radiance = throughput[0] * share, 0.0
            for _ in range(depth):
                si = scene.ray_intersect(ray)
                if not si.is_valid():
                    radiance = weight * emitter.radiance(ray.o, ray.d, ray.wavelengths, True, footprint)[0]
                    break
                bs, bw = si.bsdf(ray).sample(ctx, si, float(rng.random()), mi.Point2f(rng.random(), rng.random()))
                weight *= bw[0]
                if weight == 0.0:
                    break
                ray = continue_ray(si, ray, bs.wo)
            for c, w in enumerate(sensor.channel_weights(band)):
                out[pixel * nc + c] += radiance * w
    return out
