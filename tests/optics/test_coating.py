"""Thin-film coatings (`optics.coating`): the transfer-matrix reflectance against closed forms and an
independent route (the Airy sum of multiple reflections, computed here; the `tmm` package where it is
installed), energy conservation, the lens-file schema and its round trips, Zemax COAT lines."""

import itertools
import math

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.errors import SolasError
from solas_mi.optics import coating
from solas_mi.optics.glass import resolve

BK7 = resolve("N-BK7")


def test_quarter_wave_mgf2_on_bk7_equals_the_closed_form():
    """The issue's acceptance: ((n0 ns − n1²)/(n0 ns + n1²))² at the design wavelength, normal incidence."""
    c = coating.coating_from_table({"kind": "quarter_wave", "material": "MgF2", "design_nm": 550.0}, "t")
    n1, ns = float(coating.MATERIALS["MGF2"].index(550.0)), float(BK7.index(550.0))
    closed = ((ns - n1**2) / (ns + n1**2)) ** 2
    p = c.power(1.0, ns, 550.0, 1.0)
    assert abs(p.rs - closed) < 1e-9 and abs(p.rp - closed) < 1e-9
    assert 0.012 < closed < 0.014  # MgF2 on BK7: about 1.3 %, against the bare 4.2 %


def test_matched_quarter_wave_reflects_nothing_and_is_the_minimum():
    """n1² = n0 ns: zero reflectance at the design wavelength, the minimum of R(λ)."""
    ns = 1.69
    layer = [np.sqrt(ns) + 0j]
    lam = np.linspace(400.0, 800.0, 401)
    r = coating.stack_power(1.0, layer, [600.0 / (4.0 * math.sqrt(ns))], ns, lam, 1.0).reflectance
    assert r[lam == 600.0][0] < 1e-28
    assert lam[np.argmin(r)] == 600.0


def test_bare_interface_is_fresnel_and_brewster():
    n = 1.5
    theta = np.radians(np.linspace(0.0, 89.0, 90))
    p = coating.stack_power(1.0, [], [], n, 550.0, np.cos(theta))
    cos_t = np.sqrt(1.0 - (np.sin(theta) / n) ** 2)
    rs = ((np.cos(theta) - n * cos_t) / (np.cos(theta) + n * cos_t)) ** 2
    rp = ((n * np.cos(theta) - cos_t) / (n * np.cos(theta) + cos_t)) ** 2
    np.testing.assert_allclose(p.rs, rs, atol=1e-14)
    np.testing.assert_allclose(p.rp, rp, atol=1e-14)
    assert abs(p.rs[0] - ((n - 1) / (n + 1)) ** 2) < 1e-15
    brewster = math.atan(n)
    assert coating.stack_power(1.0, [], [], n, 550.0, math.cos(brewster)).rp < 1e-30
    np.testing.assert_allclose(p.rs + p.ts, 1.0, atol=1e-14)  # lossless: R + T = 1
    np.testing.assert_allclose(p.rp + p.tp, 1.0, atol=1e-14)


def _airy(n0, layers, thicknesses, ns, lam, cos0, pol):
    """An independent route: the stack's amplitude reflection by adding one film at a time from the
    substrate out, r = (r_ij + r' e^{-2iδ}) / (1 + r_ij r' e^{-2iδ}) (the Airy sum), with Fresnel
    coefficients of each interface (n − ik convention, forward-decaying branch)."""
    media = [complex(n0)] + list(layers) + [complex(ns)]
    kx = n0 * math.sqrt(1.0 - cos0**2)
    ycos = []
    for m in media:
        y = np.sqrt(m * m - kx * kx + 0j)
        ycos.append(-y if y.imag > 0 else y)  # N cos θ

    def fresnel(i):
        a, b = media[i], media[i + 1]
        if pol == "s":
            return (ycos[i] - ycos[i + 1]) / (ycos[i] + ycos[i + 1])
        return (b * b * ycos[i] - a * a * ycos[i + 1]) / (b * b * ycos[i] + a * a * ycos[i + 1])

    r = fresnel(len(media) - 2)
    for j in range(len(layers), 0, -1):
        phase = np.exp(-2j * 2 * math.pi * ycos[j] * thicknesses[j - 1] / lam)
        rij = fresnel(j - 1)
        r = (rij + r * phase) / (1 + rij * r * phase)
    return abs(r) ** 2


FOUR_LAYER = [
    {"material": "MGF2", "thickness_nm": 94.0},
    {"material": "model:2.1", "thickness_nm": 127.0},
    {"material": "model:1.62", "thickness_nm": 80.0},
    {"material": "model:2.35", "thickness_nm": 14.0},
]


@pytest.mark.parametrize("absorbing", [False, True])
def test_four_layer_stack_equals_the_airy_sum(absorbing):
    """A four-layer broadband stack (MgF2 / H / M / H, an absorbing one where asked) against the Airy sum
    over 380-780 nm and 0-70 degrees, s and p."""
    rows = [dict(r) for r in FOUR_LAYER]
    if absorbing:
        rows[1]["k"] = 0.05
    c = coating.coating_from_table({"kind": "stack", "layers": rows}, "t")
    for lam in (380.0, 455.0, 531.0, 640.0, 780.0):
        ns = float(BK7.index(lam))
        indices = [layer.index(lam) for layer in c.layers]
        for deg in (0.0, 20.0, 45.0, 70.0):
            cos0 = math.cos(math.radians(deg))
            p = c.power(1.0, ns, lam, cos0)
            assert abs(p.rs - _airy(1.0, indices, [f.thickness_nm for f in c.layers], ns, lam, cos0, "s")) < 1e-12
            assert abs(p.rp - _airy(1.0, indices, [f.thickness_nm for f in c.layers], ns, lam, cos0, "p")) < 1e-12
            absorbed_s, absorbed_p = 1.0 - p.rs - p.ts, 1.0 - p.rp - p.tp
            if absorbing:  # R + T + A = 1 with A > 0 and below the single pass through the film
                assert 0 < absorbed_s < 0.5 and 0 < absorbed_p < 0.5
            else:
                assert abs(absorbed_s) < 1e-12 and abs(absorbed_p) < 1e-12


def test_four_layer_stack_equals_the_tmm_package():
    """The issue's acceptance: within 1e-6 of an independent transfer-matrix code over 380-780 nm, 0-70°,
    s and p (the `tmm` package, where installed: a test-only check)."""
    tmm = pytest.importorskip("tmm")
    c = coating.coating_from_table({"kind": "stack", "layers": FOUR_LAYER}, "t")
    for lam in np.linspace(380.0, 780.0, 9):
        ns = float(BK7.index(lam))
        n_list = [1.0] + [complex(layer.index(lam)).conjugate() for layer in c.layers] + [ns]  # tmm: n + ik
        d_list = [np.inf] + [f.thickness_nm for f in c.layers] + [np.inf]
        for deg in np.linspace(0.0, 70.0, 8):
            p = c.power(1.0, ns, lam, math.cos(math.radians(deg)))
            for pol, ours_r, ours_t in (("s", p.rs, p.ts), ("p", p.rp, p.tp)):
                ref = tmm.coh_tmm(pol, n_list, d_list, math.radians(deg), lam)
                assert abs(ours_r - ref["R"]) < 1e-6 and abs(ours_t - ref["T"]) < 1e-6


def test_glass_to_air_meets_the_layers_reversed():
    """An asymmetric absorbing stack: from the glass side the films come in reverse order (as Zemax applies
    a coating), which for a lossless stack changes nothing (reciprocity) and for an absorbing one does."""
    rows = [{"material": "MGF2", "thickness_nm": 100.0}, {"material": "model:2.0", "thickness_nm": 30.0, "k": 1.0}]
    c = coating.coating_from_table({"kind": "stack", "layers": rows}, "t")
    ns = 1.52
    inside = c.power(ns, 1.0, 550.0, 1.0)
    reversed_ = coating.stack_power(
        ns, [f.index(550.0) for f in c.layers[::-1]], [f.thickness_nm for f in c.layers[::-1]], 1.0, 550.0, 1.0
    )
    assert inside.rs == reversed_.rs
    assert abs(c.power(1.0, ns, 550.0, 1.0).ts - inside.ts) < 1e-12  # T is reciprocal, R is not
    assert abs(c.power(1.0, ns, 550.0, 1.0).rs - inside.rs) > 0.01


def test_ideal_coating():
    c = coating.coating_from_table({"kind": "ideal", "reflectance": 0.002}, "t")
    p = c.power(1.0, 1.5, np.array([400.0, 700.0]), np.array([1.0, 0.3]))
    assert np.all(p.reflectance == 0.002) and np.all(p.transmittance == 0.998)


@pytest.mark.parametrize(
    "table, words",
    [
        ({"kind": "paint"}, f"coating kind 'paint' must be one of {', '.join(coating.KINDS)}"),
        ({"kind": "ideal", "reflectance": 1.5}, "reflectance 1.5 must be a finite number from 0 to 1"),
        ({"kind": "ideal", "material": "MGF2"}, "takes no option material"),
        ({"kind": "quarter_wave", "material": "UNOBTAINIUM"}, "layer material"),
        ({"kind": "stack", "layers": []}, "must be a list of 1 to"),
        ({"kind": "stack", "layers": [{"material": "MGF2", "thickness_nm": -1.0}]}, "thickness_nm = -1.0"),
        ({"kind": "stack", "layers": [{"material": "MGF2", "thickness_nm": 1.0, "k": -0.1}]}, "k = -0.1"),
        ({"kind": "stack", "layers": [{"material": "MGF2", "thick": 1.0}]}, "unknown keys thick"),
        (3, "coating = 3 must be a kind"),
    ],
)
def test_bad_coatings_are_refused_by_name(table, words):
    with pytest.raises(SolasError, match="surface 1") as info:
        coating.coating_from_table(table, "surface 1")
    assert words in str(info.value)


COATINGS = [
    {"kind": "quarter_wave", "material": "MGF2", "design_nm": 550.0},
    {"kind": "ideal", "reflectance": 0.05},
    {
        "kind": "stack",
        "layers": [
            {"material": "MGF2", "thickness_nm": 94.0},
            {"material": "model:2.1", "thickness_nm": 127.0, "k": 0.01},
        ],
    },
]


def test_coatings_round_trip_through_toml(doublet_spec, tmp_path):
    for row, c in zip(doublet_spec["surface"], COATINGS):
        row["coating"] = c
    lens = Lens.from_dict(doublet_spec)
    assert [s.coating.table() for s in lens.surfaces[:3]] == COATINGS and lens.surfaces[3].coating is None
    again = Lens.load(lens.save(tmp_path / "coated.toml"))
    assert again.surfaces == lens.surfaces and again.hash == lens.hash
    assert (
        Lens.from_dict(
            {
                **doublet_spec,
                "surface": doublet_spec["surface"][:0]
                + [{k: v for k, v in r.items() if k != "coating"} for r in doublet_spec["surface"]],
            }
        ).hash
        != lens.hash
    )


def test_uncoated_lens_keeps_its_hash_and_none_is_the_bare_surface(doublet, doublet_spec):
    """A lens without coatings is the lens it was (its hash, hence every cache key); `none` stated is the same."""
    doublet_spec["surface"][0]["coating"] = "none"
    lens = Lens.from_dict(doublet_spec)
    assert (
        lens.hash
        == Lens.from_dict(
            dict(doublet_spec)
            | {"surface": [{k: v for k, v in r.items() if k != "coating"} for r in doublet_spec["surface"]]}
        ).hash
    )
    assert all(s.coating is None for s in lens.surfaces)
    assert (
        "coating"
        not in Lens.load("solas-doublet")
        .save(__import__("pathlib").Path(__import__("tempfile").mkdtemp()) / "d.toml")
        .read_text()
    )


def _zmx(coat: str) -> str:
    return (
        "\n".join(
            [
                "UNIT MM X W X CM MR CPMM",
                "ENPD 10",
                "WAVM 1 0.55 1",
                "SURF 0",
                "  DISZ INFINITY",
                "SURF 1",
                "  CURV 0.01",
                "  DISZ 5",
                "  GLAS N-BK7",
                "  DIAM 8",
                "  STOP",
                f"  COAT {coat} 0",
                "SURF 2",
                "  CURV -0.01",
                "  DISZ 95",
                "  DIAM 8",
                "SURF 3",
                "  DISZ 0",
            ]
        )
        + "\n"
    )


def test_zemax_ideal_coat_is_read_and_written_back(tmp_path):
    path = tmp_path / "coated.zmx"
    path.write_text(_zmx("I.95"))
    lens = Lens.load(path)
    assert lens.surfaces[0].coating.kind == "ideal"
    assert abs(lens.surfaces[0].coating.reflectance - 0.05) < 1e-15 and lens.surfaces[1].coating is None
    again = Lens.load(lens.save(tmp_path / "again.zmx"))
    assert again.surfaces[0].coating == lens.surfaces[0].coating
    assert "COAT I.95" in (tmp_path / "again.zmx").read_text()


def test_zemax_named_coating_is_refused_by_name(tmp_path):
    path = tmp_path / "named.zmx"
    path.write_text(_zmx("AR"))
    with pytest.raises(SolasError, match="COAT 'AR' names a coating of a Zemax coating file"):
        Lens.load(path)


def test_formats_without_coatings_refuse_a_coated_lens(doublet_spec, tmp_path):
    doublet_spec["surface"][0]["coating"] = COATINGS[0]
    lens = Lens.from_dict(doublet_spec)
    with pytest.raises(SolasError, match="holds no coatings"):
        lens.save(tmp_path / "x.dat")
    with pytest.raises(SolasError, match="quarter_wave coating has no .zmx form"):
        lens.save(tmp_path / "x.zmx")


def plate(front=None, back=None, thickness=5.0, material="N-BK7"):
    """A plane-parallel plate in air, the stop on its front face, coatings where given."""
    rows = [
        {"radius": 0.0, "thickness": thickness, "diameter": 20.0, "material": material, "stop": True},
        {"radius": 0.0, "thickness": 50.0, "diameter": 20.0},
    ]
    for row, c in zip(rows, (front, back)):
        if c is not None:
            row["coating"] = c
    return Lens.from_dict({"name": "plate", "surface": rows})


@pytest.mark.parametrize("variant", ["llvm", "python"])
def test_the_tracer_weighs_each_refraction_by_its_coating(variant):
    """trace(fresnel=True) through a coated plate: the product of the coatings' transmittances at the
    refraction angles (Snell: n sin θ conserved), from the transfer matrix in NumPy; the uncoated face
    keeps Fresnel's."""
    from solas_mi.optics import tracer

    lens = plate(COATINGS[2], None)
    n = float(lens.surfaces[0].glass.index(531.0))
    for deg in (0.0, 25.0, 50.0):
        tan = math.tan(math.radians(deg))
        if variant == "llvm":
            rays = tracer.launch(lens, tracer.F(0.0), tracer.F(tan), tracer.F(0.0), tracer.F(0.5))
            got = tracer.to_numpy(tracer.trace(lens, rays, tracer.F(0.531), fresnel=True).transmittance)[0][0]
        else:
            rays = tracer.launch(lens, 0.0, tan, 0.0, 0.5)
            got = tracer.trace(lens, rays, 0.531, fresnel=True).transmittance
        cos_air = math.cos(math.radians(deg))
        cos_glass = math.sqrt(1.0 - (math.sin(math.radians(deg)) / n) ** 2)
        front = lens.surfaces[0].coating.power(1.0, n, 531.0, cos_air).transmittance
        back = coating.stack_power(n, [], [], 1.0, 531.0, cos_glass).transmittance
        assert abs(got - front * back) < (2e-6 if variant == "llvm" else 1e-12)


def test_an_uncoated_lens_keeps_the_bare_fresnel_transmittance(doublet):
    """No coating, the bare interface: the on-axis ray (normal incidence at every surface) keeps the
    product of Fresnel's 4 n n' / (n + n')² (its bit-identity with the code before coatings was checked
    against that code's PSFs and traces, the change's report)."""
    from solas_mi.optics import tracer

    rays = tracer.launch(doublet, tracer.F(0.0), tracer.F(0.0), tracer.F(0.0), tracer.F(0.0))
    traced = tracer.trace(doublet, rays, tracer.F(0.531), fresnel=True)
    n = doublet.indices(531.0)
    expected = np.prod([4 * a * b / (a + b) ** 2 for a, b in itertools.pairwise(n) if a != b])
    assert abs(tracer.to_numpy(traced.transmittance)[0][0] - expected) < 1e-15


def test_lens_info_states_coatings_and_the_on_axis_transmittance(doublet_spec, tmp_path, capsys):
    """The on-axis chief ray meets every surface at normal incidence: its transmittance is the product of
    each crossing's normal-incidence T, coated or bare (Fresnel: 4 n n' / (n + n')²)."""
    from solas_mi.cli import main

    doublet_spec["surface"][0]["coating"] = {"kind": "ideal", "reflectance": 0.01}
    lens = Lens.from_dict(doublet_spec)
    path = lens.save(tmp_path / "coated.toml")
    assert main(["lens", "info", str(path)]) == 0
    printed = capsys.readouterr().out
    w = lens.primary_wavelength
    n = lens.indices(w)
    bare = [4 * a * b / (a + b) ** 2 for a, b in itertools.pairwise(n) if a != b]
    line = next(t for t in printed.splitlines() if t.startswith("coatings: "))
    assert f"{0.99 * np.prod(bare[1:]):.4f} (bare surfaces: {np.prod(bare):.4f})" in line
    assert main(["lens", "info", "solas-doublet"]) == 0  # bare: said so, the typical AR beside (`typical_ar`)
    assert "coatings: none stated (bare glass" in capsys.readouterr().out


def test_an_opaque_metal_film_reflects_as_the_bulk_metal_and_passes_nothing():
    """A thick absorbing film (aluminium-like N = 1 − 7i, 0.1 mm) is the bulk metal: R = |(n0 − N)/(n0 + N)|²
    (Fresnel with a complex index), T = 0, A = 1 − R, every number finite; it overflowed to NaN before."""
    c = coating.coating_from_table(
        {"kind": "stack", "layers": [{"material": "model:1.0001", "thickness_nm": 1e5, "k": 7.0}]}, "t"
    )
    n = complex(c.layers[0].index(550.0))
    p = c.power(1.0, 1.5, 550.0, np.array([1.0, 0.5]))
    assert np.all(np.isfinite(p.rs)) and np.all(np.isfinite(p.ts))
    assert abs(p.rs[0] - abs((1.0 - n) / (1.0 + n)) ** 2) < 1e-12 and np.all(p.ts == 0.0)
    absorbed = 1.0 - p.rp - p.tp
    assert np.all((absorbed > 0.0) & (absorbed < 1.0))
