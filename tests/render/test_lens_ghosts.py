"""The lens camera's ghosts (`lens_camera` option `ghosts`, `optics.ghost_trace`, `plugins/ghost_sampling.py`):
the Dr.Jit trace of mixed paths against the sequential tracers, the ghosts in a render against the ghost
table (`psf.ghosts`), the option's refusals, and the direct image untouched with ghosts off."""

import hashlib
import math

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.optics import ghost_paths, ghost_trace, tracer
from solas_mi.optics.exit_pupil import reversed_lens
from solas_mi.psf.stray_light import ghosts

DOUBLE_GAUSS = "double-gauss-50mm"
LAM = 587.5618  # the double Gauss's primary wavelength (nm): the ghost table's and the mono render's
FILM = (128, 96)  # columns, rows: the film spans the lens's ±22° across
DISTANCE_M = 1e4  # the light: a sphere this far (m), ANGULAR_RADIUS_DEG in radius
ANGULAR_RADIUS_DEG = 1.0


def film_rays(lens, count, seed=1):
    """Rays from film points toward points of the last surface's vertex plane, in the reversed lens (as the
    lens camera launches them), and their wavelengths (µm)."""
    rng = np.random.default_rng(seed)
    rev = reversed_lens(lens)
    film = rng.uniform(-8.0, 8.0, (2, count))
    target = rng.uniform(-12.0, 12.0, (2, count))
    rays = tracer.launch(rev, None, None, tracer.F(target[0]), tracer.F(target[1]), tuple(map(tracer.F, film)))
    return rev, rays, tracer.F(np.full(count, LAM * 1e-3))


def test_the_direct_path_is_the_tracers_bit_for_bit():
    """Rays on the direct path (`first` = `second` = the surface count) arrive where `tracer.trace` takes them,
    with its Fresnel transmittance, to the last bit, and the same rays pass."""
    rev, rays, lam = film_rays(Lens.load(DOUBLE_GAUSS), 4000)
    ref = tracer.trace(rev, rays, lam, fresnel=True)
    n = ghost_trace.direct(rev)
    out, ok, weight = ghost_trace.trace_paths(rev, rays, lam, tracer.UInt32(np.full(4000, n)), tracer.UInt32(n))
    passed = np.asarray(ref.ok & (ref.clipped_by == 0))
    assert passed.sum() > 500 and np.array_equal(np.asarray(ok), passed)
    for name in ("x", "y", "z", "dx", "dy", "dz"):
        assert np.array_equal(np.asarray(getattr(out, name))[passed], np.asarray(getattr(ref.rays, name))[passed])
    assert np.array_equal(np.asarray(weight)[passed], np.asarray(ref.transmittance)[passed])


def test_mixed_paths_follow_the_numpy_ghost_tracer():
    """A wavefront of rays on three different paths (a ghost each, the direct one): each ray where
    `ghost_paths.trace` takes it along its own path, within 1e-12 mm, with its power within 1e-15."""
    rev, rays, lam = film_rays(Lens.load(DOUBLE_GAUSS), 6000)
    every = ghost_paths.paths(rev)
    chosen = [every[0], every[len(every) // 2], None]
    n = ghost_trace.direct(rev)
    which = np.arange(6000) % 3
    first = np.array([n if p is None else p[0] for p in chosen])[which]
    second = np.array([n if p is None else p[1] for p in chosen])[which]
    out, ok, weight = ghost_trace.trace_paths(rev, rays, lam, tracer.UInt32(first), tracer.UInt32(second))
    start = ghost_paths.Rays(
        *(np.asarray(v) for v in (rays.x, rays.y, rays.z, rays.dx, rays.dy, rays.dz)),
        np.ones(6000),
        np.ones(6000, bool),
    )
    arrived = 0
    for k, path in enumerate(chosen):
        ref = ghost_paths.trace(rev, path, start, LAM)
        ids = ref.ids[ref.alive]
        mine = np.flatnonzero(np.asarray(ok) & (which == k))
        assert np.array_equal(np.sort(ids[which[ids] == k]), mine)
        at = ref.alive & (which[ref.ids] == k)
        for name in ("x", "y", "dx", "dy", "dz"):
            assert np.abs(np.asarray(getattr(out, name))[ref.ids[at]] - getattr(ref, name)[at]).max() < 1e-12
        assert np.abs(np.asarray(weight)[ref.ids[at]] - ref.power[at]).max() < 1e-15
        arrived += len(mine)
    assert arrived > 1000


def light_scene(mi, field_deg, ghosts_value, spp):
    """The double Gauss's lens camera (mono at LAM) and a sphere of radiance 1 at `field_deg` (x, y), far."""
    tx, ty = (math.tan(math.radians(f)) for f in field_deg)
    sensor = {
        "type": "lens_camera",
        "lens": DOUBLE_GAUSS,
        "response": f"mono:{LAM}",
        "fresnel": "transmit",
        "film": {
            "type": "hdrfilm",
            "width": FILM[0],
            "height": FILM[1],
            "rfilter": {"type": "box"},
            "pixel_format": "luminance",
        },
        "sampler": {"type": "independent", "sample_count": spp},
    }
    if ghosts_value is not None:
        sensor["ghosts"] = ghosts_value
    # light from the lens frame's direction (tx, ty, 1) comes from (−tx, −ty, −1) D; the camera frame is (x, −y, −z)
    centre = [-tx * DISTANCE_M, ty * DISTANCE_M, DISTANCE_M]
    radius = DISTANCE_M * math.hypot(1.0, tx, ty) * math.radians(ANGULAR_RADIUS_DEG)
    light = {"type": "area", "radiance": {"type": "uniform", "value": 1.0}}
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 1},
            "sensor": sensor,
            "light": {"type": "sphere", "center": centre, "radius": radius, "emitter": light},
        }
    )


def rendered(mi, scene, spp, seed=0):
    return np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)[..., 0]


def table_on_film(report, pitch_mm, path):
    """A ghost of the table as the film catches it: its energy (a fraction of the direct image's) and
    centroid (column, row) from its rays that land on the film."""
    x, y, w = report.hits[path]
    col, row = x / pitch_mm + FILM[0] / 2, FILM[1] / 2 - y / pitch_mm
    on = (col >= 0) & (col < FILM[0]) & (row >= 0) & (row < FILM[1])
    return w[on].sum(), (np.average(col[on], weights=w[on]), np.average(row[on], weights=w[on]))


def centroid(image):
    rows, cols = np.indices(image.shape)
    return (cols * image).sum() / image.sum() + 0.5, (rows * image).sum() / image.sum() + 0.5


@pytest.mark.slow
@pytest.mark.parametrize("field_deg", [(0.0, 0.0), (0.0, 8.0), (6.0, -5.0)])
def test_rendered_ghosts_match_the_ghost_table(variant_llvm_ad_mono, field_deg):
    """A far light at three fields through the double Gauss (bare glass: Fresnel): the five ghosts that put
    the most light on the film, each rendered alone (`ghosts` "j,i"), land within 1 pixel of the ghost
    table's centroid and carry its energy (relative to the direct image) within 5 %; the table's rays that
    land on the film, the light's centre field."""
    mi = variant_llvm_ad_mono
    lens = Lens.load(DOUBLE_GAUSS)
    report = ghosts(lens, field_deg, wavelengths_nm=[LAM], rays=256)
    direct_scene = light_scene(mi, field_deg, None, 64)
    pitch = direct_scene.sensors()[0].pitch_mm
    direct = rendered(mi, direct_scene, 64)
    expected = np.array(report.direct_centroid_mm) / pitch * [1, -1] + np.array(FILM) / 2
    assert np.abs(np.array(centroid(direct)) - expected).max() < 0.1
    on_film = {path: table_on_film(report, pitch, path) for path in report.hits if len(report.hits[path][2])}
    for path in sorted(on_film, key=lambda p: -on_film[p][0])[:5]:
        energy, place = on_film[path]
        image = rendered(mi, light_scene(mi, field_deg, f"{path[0] + 1},{path[1] + 1}", 1024), 1024)
        assert image.sum() / direct.sum() == pytest.approx(energy, rel=0.05), path
        assert np.hypot(*(np.array(centroid(image)) - place)) < 1.0, path


def test_ghosts_on_add_every_ghost_to_the_direct_image(variant_llvm_ad_mono):
    """With ghosts "on" a frame's light is the direct image's and every ghost's on the film (the table's),
    within 3 %; "only" is the ghosts' alone: the two estimates are unbiased mixtures of the same paths."""
    mi = variant_llvm_ad_mono
    field = (0.0, 4.0)
    report = ghosts(Lens.load(DOUBLE_GAUSS), field, wavelengths_nm=[LAM], rays=128)
    scene = light_scene(mi, field, None, 64)
    pitch = scene.sensors()[0].pitch_mm
    direct = rendered(mi, scene, 64).sum()
    stray = sum(table_on_film(report, pitch, p)[0] for p in report.hits if len(report.hits[p][2]))
    on = rendered(mi, light_scene(mi, field, "on", 512), 512).sum() / direct
    only = rendered(mi, light_scene(mi, field, "only", 512), 512).sum() / direct
    assert on == pytest.approx(1.0 + stray, rel=0.03) and only == pytest.approx(stray, rel=0.03)


def test_ghosts_off_leave_the_camera_rays_bit_identical(variant_llvm_ad_spectral):
    """`ghosts` "off" given is the camera without the option, to the last bit: no sampler is built, and the
    rays and weights of `sample_ray` for the same samples are equal (the direct trace is `tracer.trace`'s own;
    against the code before ghosts: docs/details/stray_light.md). Rays, not renders: Mitsuba's film adds a
    pixel's samples in an order that varies from run to run."""
    mi = variant_llvm_ad_spectral
    rng = np.random.default_rng(5)
    s1, s2x, s2y, s3x, s3y = (rng.random(4096).astype(np.float32) for _ in range(5))
    hashes = set()
    for value in (None, "off", "OFF"):
        sensor = {"type": "lens_camera", "lens": DOUBLE_GAUSS, "fresnel": "transmit"}
        camera = mi.load_dict(sensor if value is None else {**sensor, "ghosts": value})
        assert camera.ghosts is None
        ray, weight = camera.sample_ray(mi.Float(0.0), mi.Float(s1), mi.Point2f(s2x, s2y), mi.Point2f(s3x, s3y))
        values = [ray.o.x, ray.o.y, ray.o.z, ray.d.x, ray.d.y, ray.d.z, ray.maxt, *(weight[i] for i in range(4))]
        hashes.add(hashlib.sha256(b"".join(np.asarray(v).tobytes() for v in values)).hexdigest())
        assert np.asarray(weight[0]).sum() > 0
    assert len(hashes) == 1


@pytest.mark.parametrize(
    "extra, message",
    [
        ({"ghosts": "sometimes"}, "ghosts 'sometimes' must be one of off, on, only or a path j,i"),
        ({"ghosts": "5,7"}, "ghosts '5,7' must be one of"),
        ({"ghosts": "on", "fresnel": "off"}, "fresnel 'off' \\(lossless surfaces\\) reflects nothing"),
    ],
)
def test_bad_ghosts_are_refused_by_name(variant_llvm_ad_mono, extra, message):
    mi = variant_llvm_ad_mono
    sensor = {"type": "lens_camera", "lens": DOUBLE_GAUSS, "response": f"mono:{LAM}", **extra}
    with pytest.raises(RuntimeError, match=message):  # Mitsuba wraps the plugin's SolasError
        mi.load_dict({"type": "scene", "sensor": sensor})


def test_ghosts_in_a_scalar_variant_are_refused_by_name(variant_scalar_spectral):
    """The ghost paths are drawn and traced per wavefront (gathers over the path table): a scalar variant, one
    ray at a time, is refused naming the JIT variants."""
    sensor = {"type": "lens_camera", "lens": DOUBLE_GAUSS, "ghosts": "on"}
    with pytest.raises(RuntimeError, match="ghosts need a JIT variant .* not scalar_spectral"):
        variant_scalar_spectral.load_dict({"type": "scene", "sensor": sensor})


def ghost_noise(images, region):
    """The relative noise per pixel of `images` (two renders at other seeds) inside `region`: the rms of
    their difference over √2, over their mean there."""
    a, b = images
    return np.sqrt(np.mean((a[region] - b[region]) ** 2 / 2.0)) / (0.5 * (a[region] + b[region])).mean()


def test_ghosts_guided_toward_a_small_emitter_are_unbiased_and_less_noisy(variant_llvm_ad_mono):
    """A far light of 1° radius at 8° (`light_scene`): the stray light with the pupil points of the ghosts drawn
    toward it (`ghost_guide`) against the camera that draws them uniformly on the square (no guide: its `aim`
    left out), at the same 64 spp, two seeds each. In the brightest tenth of the stray light (from a third,
    independent guided render) both estimate the same light (their sums within 5 standard errors of the
    difference, each image's from its pixels' spread between seeds), and the guided one's relative noise per
    pixel is at least 4× lower (measured: 0.13 against 1.35)."""
    mi = variant_llvm_ad_mono
    spp, field = 64, (0.0, 8.0)
    renders = {}
    for guided in (True, False):
        scene = light_scene(mi, field, "only", spp)
        sampler = scene.sensors()[0].ghosts
        if not guided:
            sampler.aim = lambda *args: None
        renders[guided] = [rendered(mi, scene, spp, seed) for seed in (0, 1, 2)[: 3 if guided else 2]]
        assert (sampler.guide is not None) == guided
    chooser = renders[True].pop()
    region = chooser >= np.quantile(chooser[chooser > 0], 0.9)
    sums = {g: np.mean([image[region].sum() for image in renders[g]]) for g in renders}
    # a pixel's variance from its two seeds, (a − b)²/2; the mean of two images' sums: their sum over 4
    error = math.sqrt(sum(((a[region] - b[region]) ** 2).sum() / 4.0 for a, b in renders.values()))
    assert abs(sums[True] - sums[False]) <= 5.0 * error
    assert ghost_noise(renders[True], region) * 4.0 <= ghost_noise(renders[False], region)
