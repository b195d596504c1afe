"""The shipped lenses state their coatings as their sources do, none; `lens info` says so and gives their on-axis
transmittance with the typical single-layer AR (`optics.typical_ar`) beside the bare one, against the closed form
of a quarter-wave layer at its design wavelength."""

import itertools
import re
from dataclasses import replace

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.cli import main
from solas_mi.optics import coating, typical_ar
from solas_mi.resources import resource_dir

SHIPPED = sorted(p.stem.replace("_", "-") for p in (resource_dir("scenes") / "lenses").glob("*.toml"))


def _closed_form(lens: Lens, w: float) -> float:
    """The on-axis transmittance with MgF2 a quarter wave at w on every air-glass surface: 1 - ((n0 ns - n1²)/(n0 ns
    + n1²))² there, 1 - ((n - n')/(n + n'))² at a cemented (bare) one."""
    n1 = float(coating.MATERIALS["MGF2"].index(w))
    media = [lens.object_glass] + [s.glass for s in lens.surfaces]
    t = 1.0
    for a, b in itertools.pairwise(media):
        na, nb = float(a.index(w)), float(b.index(w))
        if a != b:
            air = min(na, nb) == 1.0
            r = ((na * nb - n1**2) / (na * nb + n1**2)) ** 2 if air else ((na - nb) / (na + nb)) ** 2
            t *= 1.0 - r
    return t


@pytest.mark.parametrize("name", ["solas-doublet", "cooke-triplet"])
def test_the_typical_ar_transmittance_is_the_closed_form(name):
    lens = Lens.load(name)
    at_design = replace(lens, wavelengths_nm=(typical_ar.TYPICAL_AR["design_nm"],))
    text = typical_ar.note(at_design)["coatings"]
    coated, bare = (
        float(v) for v in re.findall(r"transmittance at 550 nm ([\d.]+) \(bare surfaces: ([\d.]+)\)", text)[0]
    )
    assert coated == pytest.approx(_closed_form(lens, 550.0), abs=6e-5)  # 4 decimals printed
    assert bare < coated


def test_only_air_glass_surfaces_are_coated():
    doublet = Lens.load("solas-doublet")
    coated = typical_ar.with_typical_ar(doublet)
    assert [s.coating is not None for s in coated.surfaces] == [True, False, True, False]  # cemented, stop: bare
    assert typical_ar.note(coated) == {}  # a lens that states coatings: its own line (`coating.metadata`)


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_lens_states_bare_surfaces_in_lens_info(name, capsys):
    lens = Lens.load(name)
    assert all(s.coating is None for s in lens.surfaces)  # as their sources: every figure stays theirs
    assert main(["lens", "info", name]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("coatings: "))
    assert "none stated" in line and f"on its {len(typical_ar.air_glass(lens))} air-glass surfaces" in line
    assert np.isfinite(float(re.search(r"transmittance at [\d.]+ nm ([\d.]+)", line).group(1)))


def test_lens_convert_states_the_typical_ar(tmp_path, capsys):
    from solas_mi.cli import build_parser

    convert = build_parser()._subparsers._group_actions[0].choices["lens"]._subparsers._group_actions[0]
    ar = typical_ar.TYPICAL_AR
    helps = " ".join(convert.choices["convert"].format_help().split())  # the lines joined
    assert f"{ar['material']} a quarter wave at {ar['design_nm']:g} nm" in helps
    out = tmp_path / "coated.toml"
    assert main(["lens", "convert", "cooke-triplet", "--typical-ar", "-o", str(out)]) == 0
    coated, expected = Lens.load(out), typical_ar.with_typical_ar(Lens.load("cooke-triplet"))
    assert coated.surfaces == expected.surfaces and coated.hash == expected.hash
    assert f"hash {coated.hash}" in capsys.readouterr().out


def test_a_lens_coated_already_is_given_back_unchanged(tmp_path, capsys):
    """--typical-ar on a lens whose every air-glass surface states a coating adds none: the lens comes back as it
    is (converting a converted file once wrote "NAME (typical AR) (typical AR)", naming a second coating that was
    never added)."""
    once = typical_ar.with_typical_ar(Lens.load("solas-doublet"))
    assert typical_ar.with_typical_ar(once) is once
    first, second = tmp_path / "once.toml", tmp_path / "twice.toml"
    assert main(["lens", "convert", "solas-doublet", "--typical-ar", "-o", str(first)]) == 0
    assert main(["lens", "convert", str(first), "--typical-ar", "-o", str(second)]) == 0
    assert Lens.load(second).name == Lens.load(first).name == once.name
