"""A coated lens as Mitsuba meshes (`coated_dielectric`, `render.scene`): a coated plane-parallel plate
reflects and transmits what the coatings' transfer matrices say, path by path, within Monte Carlo error
(`fresnel` "sample") or exactly ("transmit"); a coated doublet's render-image brightness is the tracer's
transmittance; an uncoated surface keeps `sellmeier_dielectric`."""

import math

import numpy as np
import pytest

from solas_mi import Lens

THICKNESS, WAVELENGTH, DEG = 5.0, 600.0, 20.0
COATINGS = {
    # a quarter wave of high-index glass on N-BK7: an enhanced reflector (R ≈ 0.15 at its design wavelength)
    "reflector": {"kind": "quarter_wave", "material": "N-LASF9", "design_nm": 550.0},
    # an absorbing film: R + T < 1, and R differs from the two sides
    "absorber": {"kind": "stack", "layers": [{"material": "N-BK7", "thickness_nm": 8.0, "k": 1.5}]},
}


def plate(c):
    """A plane-parallel N-BK7 plate in air, both faces coated with `c`, the stop on its front face."""
    rows = [
        {"radius": 0.0, "thickness": THICKNESS, "diameter": 20.0, "material": "N-BK7", "stop": True, "coating": c},
        {"radius": 0.0, "thickness": 50.0, "diameter": 20.0, "coating": c},
    ]
    return Lens.from_dict({"name": "plate", "surface": rows})


def closed_forms(lens):
    """The plate's paths at DEG from its faces' transfer matrices (each face's R and T from the side the light
    meets it): back from the front face R₁, back through the front after the back face T₁R₂T₁', straight
    through T₁T₂, the ghost after reflections at the back face and the front face from inside T₁R₂R₁'T₂."""
    n = float(lens.surfaces[0].glass.index(WAVELENGTH))
    cos_a = math.cos(math.radians(DEG))
    cos_g = math.sqrt(1.0 - (math.sin(math.radians(DEG)) / n) ** 2)
    c = lens.surfaces[0].coating
    enter = c.power(1.0, n, WAVELENGTH, cos_a)  # air → glass at θ
    leave = c.power(n, 1.0, WAVELENGTH, cos_g)  # glass → air at θ' (the layers met in reverse)
    r1, t1, r_in, t_out = (
        float(v) for v in (enter.reflectance, enter.transmittance, leave.reflectance, leave.transmittance)
    )
    return {"front": r1, "back": t1 * r_in * t_out, "direct": t1 * t_out, "ghost": t1 * r_in * r_in * t_out}


def walk_plate(lens, fresnel: str, rays: int, seed: int = 0):
    """Rays at DEG through the plate's meshes: per ray its weight where it left and which way ("front",
    "back": toward the object after one reflection at that face; "direct", "ghost": toward the image after
    none or two), from `render.psf.walk`."""
    import drjit as dr
    import mitsuba as mi

    from solas_mi.render.psf import lens_geometry, walk

    scene = lens_geometry(lens, fresnel=fresnel)
    rng = np.random.default_rng(seed)
    r, phi = 3.0 * np.sqrt(rng.random(rays)), 2 * math.pi * rng.random(rays)
    tan = math.tan(math.radians(DEG))
    x, y, z = r * np.cos(phi), r * np.sin(phi) - 0.5 * tan, np.full(rays, -0.5)
    d = np.array([0.0, math.sin(math.radians(DEG)), math.cos(math.radians(DEG))])
    ray = mi.Ray3f(mi.Point3f(x, y, z), mi.Vector3f(*(np.full(rays, v) for v in d)), 0.0, mi.Spectrum(WAVELENGTH))
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(seed, rays)
    turns = {"count": mi.UInt32(0), "first_z": mi.Float(0.0)}

    def watch(si, active, ray, following):
        turned = active & (following.d.z * ray.d.z < 0)
        turns["first_z"] = dr.select(turned & (turns["count"] == 0), si.p.z, turns["first_z"])
        turns["count"] += dr.select(turned, 1, 0)

    _, out_d, out_w = walk(scene, ray, sampler, 12, watch)
    w, dz = np.asarray(out_w, dtype=np.float64), np.asarray(out_d.z)
    count, first_z = np.asarray(turns["count"]), np.asarray(turns["first_z"])
    paths = {
        "front": (dz < 0) & (count == 1) & (first_z < 0.5 * THICKNESS),
        "back": (dz < 0) & (count == 1) & (first_z > 0.5 * THICKNESS),
        "direct": (dz > 0) & (count == 0),
        "ghost": (dz > 0) & (count == 2),
    }
    return {k: np.where(m, w, 0.0) for k, m in paths.items()}


@pytest.mark.parametrize("name", sorted(COATINGS))
def test_a_coated_plate_reflects_and_transmits_the_transfer_matrix_s_shares(mi, name):
    """`fresnel` "sample": the share of the power on each path — reflected at the front face, at the back
    face, straight through, the two-reflection ghost — is the coatings' closed form within 4 Monte Carlo
    sigma (the weights' own spread over 2^17 rays); "transmit": every ray goes straight through with the
    weight T₁T₂ (the tracer's table against the matrix, float32: 1e-4)."""
    lens = plate(COATINGS[name])
    expected = closed_forms(lens)
    sampled = walk_plate(lens, "sample", 2**17)
    for path, values in sampled.items():
        sigma = values.std() / math.sqrt(len(values))
        assert abs(values.mean() - expected[path]) < 4 * sigma + 1e-7, (path, values.mean(), expected[path], sigma)
        assert values.any(), path  # every path taken: the bound above is not vacuous
    transmitted = walk_plate(lens, "transmit", 256)
    assert np.all(np.abs(transmitted["direct"] / expected["direct"] - 1) < 1e-4)
    assert not any(transmitted[k].any() for k in ("front", "back", "ghost"))


def test_an_absorbing_coating_absorbs(mi):
    """The absorbing film's faces reflect and transmit less than all (R + T < 1 from either side), so the test
    above checks the weight T/(1 − R) of a sampled refraction, and its R differs by side."""
    lens = plate(COATINGS["absorber"])
    n = float(lens.surfaces[0].glass.index(WAVELENGTH))
    c = lens.surfaces[0].coating
    enter, leave = c.power(1.0, n, WAVELENGTH, 1.0), c.power(n, 1.0, WAVELENGTH, 1.0)
    assert enter.reflectance + enter.transmittance < 0.95 and leave.reflectance + leave.transmittance < 0.95
    assert abs(enter.reflectance - leave.reflectance) > 0.02


def test_a_coated_doublet_renders_its_traced_transmittance(doublet_spec):
    """`render_image --fresnel transmit` of a white object through the doublet, MgF2 quarter waves on its air
    faces: the centre pixels' ratio to the lossless render is the tracer's transmittance (`trace(fresnel=True)`:
    the coatings' table, Fresnel at the cemented face) averaged over the on-axis pupil, within 0.5 %; the bare
    doublet's is Fresnel's, and lower."""
    from solas_mi.optics import tracer
    from solas_mi.optics.paraxial import paraxial
    from solas_mi.render.image import render_image

    for k in (0, 2):
        doublet_spec["surface"][k]["coating"] = {"kind": "quarter_wave", "material": "MGF2", "design_nm": 531.0}
    coated, bare = (
        Lens.from_dict(doublet_spec),
        Lens.from_dict(
            {
                **doublet_spec,
                "surface": [{k: v for k, v in s.items() if k != "coating"} for s in doublet_spec["surface"]],
            }
        ),
    )
    ratios, traced = {}, {}
    for name, lens in (("coated", coated), ("bare", bare)):
        centre = {}
        for fresnel in ("off", "transmit"):
            image = render_image(
                lens,
                np.ones((4, 4)),
                sensor=(4, 4),
                spp=1024,
                response="mono:531",
                fresnel=fresnel,
                variant="llvm_ad_spectral",
            ).image
            centre[fresnel] = float(image[1:3, 1:3].mean())
        ratios[name] = centre["transmit"] / centre["off"]
        radius = 0.5 * paraxial(lens).entrance_pupil_diameter_mm
        ex, ey = (a.ravel() * radius for a in np.meshgrid(*2 * [np.linspace(-1, 1, 201)]))
        inside = np.hypot(ex, ey) < radius
        rays = tracer.launch(lens, tracer.F(0.0), tracer.F(0.0), tracer.F(ex[inside]), tracer.F(ey[inside]))
        out = tracer.trace(lens, rays, tracer.F(0.531), fresnel=True)
        t, ok = (np.asarray(a) for a in tracer.to_numpy(out.transmittance, out.ok))
        traced[name] = float(t[ok.astype(bool)].mean())
    for name in ratios:
        assert abs(ratios[name] / traced[name] - 1) < 0.005, (name, ratios, traced)
    assert ratios["coated"] > ratios["bare"] + 0.03


def test_uncoated_surfaces_keep_sellmeier_dielectric_and_coating_none_is_it(mi, doublet):
    """The uncoated lens's caps are `sellmeier_dielectric` as before; `coated_dielectric` with coating "none"
    samples exactly as it does (the same code, the bare interface)."""
    from solas_mi.render.scene import lens_parts

    assert {p.bsdf("sample")["type"] for p in lens_parts(doublet) if p.int_glass} == {"sellmeier_dielectric"}
    import drjit as dr

    n = 4096
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wavelengths = mi.Spectrum(531.0)
    angle = mi.Float(np.linspace(-1.5, 1.5, n))
    si.wi = mi.Vector3f(dr.sin(angle), 0.0, dr.cos(angle))
    out = []
    for kind in ("sellmeier_dielectric", "coated_dielectric"):
        bsdf = mi.load_dict({"type": kind, "int_glass": "N-BK7", "fresnel": "sample"})
        sampler = mi.load_dict({"type": "independent"})
        sampler.seed(3, n)
        bs, w = bsdf.sample(mi.BSDFContext(), si, sampler.next_1d(), sampler.next_2d())
        out.append(np.concatenate([np.asarray(a).ravel() for a in (bs.wo.x, bs.wo.z, w[0])]))
    assert np.array_equal(out[0], out[1])


def test_a_bad_coating_parameter_is_named(mi):
    with pytest.raises(RuntimeError, match="coated_dielectric: coating '\\{kind' is not a JSON table"):
        mi.load_dict({"type": "coated_dielectric", "coating": "{kind"})
    with pytest.raises(RuntimeError, match="coated_dielectric: coating"):
        mi.load_dict({"type": "coated_dielectric", "coating": "velvet"})
