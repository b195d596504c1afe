"""The path loop of the direct spectral render: camera paths from the `lens_sensor` through the glass
(`sellmeier_dielectric`) until they leave the lens; a path that escapes toward the object takes the
`image_object`'s radiance.

One wavelength per path; each sample adds response_c(λ)/p(λ) × its radiance to the channels of its
pixel (a box pixel: the mean irradiance over the pixel's area, in units of the ideal camera's).
JIT variants trace a pass as one wavefront, with pixel positions, pupil points and wavelengths
stratified per pixel (`sampling`), so a pixel's samples form one stratified set however many passes
they take; the scalar reference variant runs the same estimator one independent sample at a time.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import SolasError
from .mitsuba import check_run, pass_seed
from .scene import SPAWN_OFFSET_MM, path_depth

_SAMPLES_PER_PASS = 1 << 21  # samples traced at once at most: bounds a pass's memory
# path steps (samples × interactions per path) traced at once at most: bounds a pass's time, between passes a
# signal (Ctrl-C, SIGTERM) is answered (`docs/details/render.md`, "Interruptions"). Sized
# from the lens, not from a measured time, so a render's passes, and so its image, are the same on any machine.
STEPS_PER_PASS = 1 << 19
# A GPU traces 2^19 steps in a few ms, less than a pass's launch and Python overhead: the CUDA variants take
# 16 times as many (a 1280x960 render at 256 spp on an H200: 28 s in 2^19-step passes, `benchmarks/gpu_cuda.py`).
GPU_STEPS_PER_PASS = 1 << 23


def steps_per_pass(variant: str) -> int:
    """The path steps a pass traces at most in Mitsuba variant `variant`."""
    return GPU_STEPS_PER_PASS if variant.startswith("cuda") else STEPS_PER_PASS


@dataclass
class Render:
    """A rendered image and what produced it.

    Parameters
    ----------
    image : numpy.ndarray
        H×W×C float32 in image orientation; a lens render's values are image irradiance in units of the
        ideal camera's.
    channels : tuple of str
        The channels' names (the response's, or the film's).
    spp : int
        Samples per pixel.
    seconds : float
        The render's wall-clock time (s).
    samples_per_second : float
        Pixels × spp / seconds.
    meta : dict, optional
        What produced it: variant, lens, camera, settings.
    layers : dict, optional
        More H×W channels written beside the image's (the labels, `render.labels`), name → array.
    """

    image: np.ndarray
    channels: tuple[str, ...]
    spp: int
    seconds: float
    samples_per_second: float
    meta: dict = field(default_factory=dict)
    layers: dict = field(default_factory=dict)

    def write(self, path: str, png: str | None = None) -> str:
        """Write the image as OpenEXR and an sRGB PNG, each whole or not at all.

        Parameters
        ----------
        path : str
            The EXR file: linear, one channel per response channel and the layers, metadata in the header.
        png : str, optional
            The PNG preview; default: beside the EXR, of the same name.

        Returns
        -------
        str
            The PNG's path.
        """
        from ..imageio import write_exr, write_png

        meta = dict(self.meta, spp=self.spp, samples_per_second=self.samples_per_second)
        write_exr(path, {**{c: self.image[..., k] for k, c in enumerate(self.channels)}, **self.layers}, meta)
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
    _check_mono(scene, sensor, objects[0])
    return sensor, objects[0]


def _check_mono(scene, sensor, emitter) -> None:
    """In a mono variant the glasses and the object take their `wavelength` parameter: SolasError unless
    it is the sensor's response's one wavelength (nm)."""
    import mitsuba as mi

    lam = sensor.response.single_wavelength
    if mi.is_spectral or lam is None:
        return
    used = {("image_object", emitter.wavelength)} | {
        ("sellmeier_dielectric", s.bsdf().wavelength) for s in scene.shapes() if hasattr(s.bsdf(), "wavelength")}
    wrong = sorted(f"{name} at {w:g} nm" for name, w in used if abs(w - lam) > 1e-6 * lam)
    if wrong:
        raise SolasError(f"Mitsuba variant {mi.variant()} renders one wavelength, the response's {lam:g} nm, but "
                         f"the scene takes {', '.join(wrong)}: set the plugins' `wavelength` to {lam:g} "
                         "(the scene's <default name=\"wavelength\">)")


def continue_ray(si, ray, wo_local):
    """The ray leaving interaction `si` in local direction `wo_local`, started SPAWN_OFFSET_MM along itself.
    (Mitsuba's spawn_ray offsets along the normal by ~1e-4 of the scene scale, up to ~10 µm here,
    which shifts refracted rays sideways.)"""
    import mitsuba as mi

    d = si.to_world(wo_local)
    return mi.Ray3f(si.p + d * SPAWN_OFFSET_MM, d, ray.time, ray.wavelengths)


def _max_depth(scene, lens) -> int:
    """Interactions a path needs (`scene.path_depth`), with room for ghosts where a glass samples them."""
    return path_depth(lens, any(getattr(shape.bsdf(), "fresnel", None) == "sample" for shape in scene.shapes()))


def render(scene, spp: int, seed: int = 0, max_depth: int | None = None, progress=None) -> Render:
    """Render a lens scene (a `lens_sensor` and one `image_object`) with `spp` samples per pixel in
    passes of bounded size; `max_depth` interactions per path (default: what the lens needs);
    `progress(done, spp)` is called after each pass."""
    import drjit as dr
    import mitsuba as mi

    check_run(spp, seed)
    sensor, emitter = _components(scene)
    if spp < max(sensor.discrete_lines, 1):
        raise SolasError(f"samples per pixel {spp} must be at least the response's {sensor.discrete_lines} lines "
                         "(each line needs its own samples)")
    width, height, channels = sensor.width, sensor.height, sensor.channels
    depth = max_depth if max_depth is not None else _max_depth(scene, sensor.lens)
    pixels, samples = width * height, min(_SAMPLES_PER_PASS, steps_per_pass(str(mi.variant())) // depth)
    per_pass = max(1, min(spp, samples // pixels))
    passes = math.ceil(spp / per_pass)
    # an image larger than a pass is traced in bands of rows, so a pass stays bounded in memory and time
    band = pixels if not dr.is_jit_v(mi.Float) else max(width, samples // width * width)
    accum = np.zeros(pixels * channels, dtype=np.float64)
    start, cpu = time.perf_counter(), time.process_time()
    done, pass_index = 0, 0
    for _ in range(passes):
        n_spp = min(per_pass, spp - done)
        for first in range(0, pixels, band):
            count = min(band, pixels - first)
            pass_index += 1
            if dr.is_jit_v(mi.Float):
                accum[first * channels:(first + count) * channels] += _wavefront_pass(
                    scene, sensor, emitter, n_spp, done, spp, seed, pass_seed(seed, pass_index), depth, first, count)
            else:
                accum += _scalar_pass(scene, sensor, emitter, n_spp, done, spp, seed, pass_seed(seed, pass_index),
                                      depth)
            if progress is not None and count < pixels:
                progress(done + n_spp * (first + count) / pixels, spp)
        done += n_spp
        if progress is not None and band >= pixels:
            progress(done, spp)
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    image = (accum / spp).reshape(height, width, channels).astype(np.float32)
    return Render(image, tuple(sensor.response.channels), spp, seconds, pixels * spp / seconds,
                  {"variant": mi.variant(), "spp": spp, "max_depth": depth, "seconds": seconds, "cpu_seconds": cpu,
                   **sensor.response.meta()})


def _line_shares(total: int, lines: int) -> list[float]:
    """Weight of a sample of each spectral line when sample s of `total` takes line s % lines: the
    response's weights assume 1/lines of the samples per line, the count may differ by one."""
    return [total / (lines * len(range(c, total, lines))) for c in range(lines)]


# many parameters: one traced wavefront's scene objects and its sample range, seeds and pixel band, each a scalar
# that the kernel takes opaque (one compiled kernel for every pass)
def _wavefront_pass(scene, sensor, emitter, spp: int, first: int, total: int, base: int, seed: int, depth: int,
                    first_pixel: int, pixels: int) -> np.ndarray:
    """Samples first…first+spp−1 of the stratified sets of `total` of pixels first_pixel… (`pixels` of
    them, row-major), traced as one wavefront; returns their per-pixel, per-channel sums."""
    import drjit as dr
    import mitsuba as mi

    from .sampling import cmj_2d, hash_seed, stratified_1d

    width, height, channels = sensor.width, sensor.height, sensor.channels
    samples = pixels * spp
    total_samples = total

    sampler = mi.load_dict({"type": "independent", "sample_count": spp})
    sampler.seed(dr.opaque(mi.UInt32, seed), samples)
    # what changes from pass to pass (and seed to seed) is opaque, not a literal: the passes run one
    # compiled kernel (a literal per pass compiled a kernel per pass, about 1 s each on CUDA)
    index, per_pixel, seed_base = dr.arange(mi.UInt32, samples), dr.opaque(mi.UInt32, spp), dr.opaque(mi.UInt32, base)
    pixel = index // per_pixel + dr.opaque(mi.UInt32, first_pixel)
    # the sample's index in its pixel's stratified set of `total`
    sample = index % per_pixel + dr.opaque(mi.UInt32, first)
    lines = sensor.discrete_lines
    if lines:  # each line gets its own stratified set, so every channel sees a stratified pupil
        line = sample % lines
        sample, total = sample // lines, -(-total // lines)
        wavelength_sample = (mi.Float(line) + 0.5) / lines
        share = dr.gather(mi.Float, mi.Float(_line_shares(total_samples, lines)), line)
    else:
        wavelength_sample = stratified_1d(sample, total, hash_seed(pixel, 2, seed_base), sampler.next_1d())
        share = mi.Float(1.0)
    film = mi.Point2f(mi.Float(pixel % width), mi.Float(pixel // width))
    # a pixel that covers at most two texels is integrated exactly by the object's footprint filter
    filtered = sensor.max_footprint <= 2.0 * emitter.tan_pitch and emitter.mapping == "rectilinear"
    jitter = mi.Point2f(0.5) if filtered else cmj_2d(sample, total, hash_seed(pixel, 1, seed_base), sampler.next_2d())
    pos = (film + jitter) / mi.ScalarPoint2f(width, height)  # type: ignore[operator]  # Mitsuba's stubs lack this mix
    footprint = sensor.footprint(sensor.film_point(pos)) if filtered else None
    aperture = cmj_2d(sample, total, hash_seed(pixel, 3, seed_base), sampler.next_2d())
    ray, throughput = sensor.pupil_ray(0.0, wavelength_sample, pos, aperture)
    _, wavelength_bin = sensor.sample_wavelength(wavelength_sample)
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
        bsdf_sample, bsdf_weight = si.bsdf(ray).sample(ctx, si, sampler.next_1d(active), sampler.next_2d(active),
                                                       active)
        weight *= bsdf_weight[0]
        active &= weight != 0.0
        ray = continue_ray(si, ray, bsdf_sample.wo)
    out = dr.zeros(mi.Float, pixels * channels)
    for channel, channel_weight in enumerate(sensor.channel_weights(wavelength_bin)):
        dr.scatter_reduce(dr.ReduceOp.Add, out, radiance * channel_weight, index // per_pixel * channels + channel)
    dr.eval(out)
    return np.asarray(out, dtype=np.float64) * 1.0  # the pass's sum over its samples


def _scalar_pass(scene, sensor, emitter, spp: int, first: int, total: int, base: int, seed: int, depth: int
                 ) -> np.ndarray:
    """`_wavefront_pass` one sample at a time, for the scalar reference variants: the same estimator with
    independent samples (no stratification), each line of a discrete response sampled equally often."""
    import mitsuba as mi

    width, height, channels = sensor.width, sensor.height, sensor.channels
    rng = np.random.default_rng([base, seed])
    out = np.zeros(width * height * channels)
    lines = sensor.discrete_lines
    shares = _line_shares(total, lines) if lines else []
    filtered = sensor.max_footprint <= 2.0 * emitter.tan_pitch and emitter.mapping == "rectilinear"
    ctx = mi.BSDFContext()
    for pixel in range(width * height):
        for k in range(spp):
            sample = first + k
            uniform = rng.random(8)
            wavelength_sample = (sample % lines + 0.5) / lines if lines else uniform[0]
            share = shares[sample % lines] if lines else 1.0
            jitter = (0.5, 0.5) if filtered else (uniform[1], uniform[2])
            pos = mi.Point2f((pixel % width + jitter[0]) / width, (pixel // width + jitter[1]) / height)
            footprint = sensor.footprint(sensor.film_point(pos)) if filtered else None
            ray, throughput = sensor.pupil_ray(0.0, wavelength_sample, pos, mi.Point2f(uniform[3], uniform[4]))
            _, wavelength_bin = sensor.sample_wavelength(wavelength_sample)
            weight, radiance = throughput[0] * share, 0.0
            for _ in range(depth):
                si = scene.ray_intersect(ray)
                if not si.is_valid():
                    radiance = weight * emitter.radiance(ray.o, ray.d, ray.wavelengths, True, footprint)[0]
                    break
                bsdf_sample, bsdf_weight = si.bsdf(ray).sample(ctx, si, float(rng.random()),
                                                               mi.Point2f(rng.random(), rng.random()))
                weight *= bsdf_weight[0]
                if weight == 0.0:
                    break
                ray = continue_ray(si, ray, bsdf_sample.wo)
            for channel, channel_weight in enumerate(sensor.channel_weights(wavelength_bin)):
                out[pixel * channels + channel] += radiance * channel_weight
    return out
