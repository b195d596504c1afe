"""The street scene and experiment: the generator is deterministic and wrote the shipped files; the
doublet's ideal 1280×960 view has enough slanted edges in every annulus; the experiment runs end to end
at a tiny size and shows the depth-dependent blur (the lens focused near matches the convolution on near
objects and not on far ones; focused at infinity the other way round)."""

from pathlib import Path
from types import SimpleNamespace

import pytest
from strict_json import strict_loads

from solas_mi.cli import main
from solas_mi.errors import SolasError
from solas_mi.experiments.street.framings import FRAMINGS, NARROW, WIDE, framing
from solas_mi.experiments.street.run import SCENE, Settings, experiment_scene, run
from solas_mi.experiments.street.scene import write_street
from solas_mi.outputs import safe_name


def files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_the_generator_wrote_the_shipped_scene_byte_for_byte(tmp_path):
    write_street(tmp_path / "a")
    written = files(tmp_path / "a")
    assert written == files(SCENE.parent)
    assert sum(len(b) for b in written.values()) < 3e6  # small enough for the repository


def test_the_shipped_scene_defaults_to_the_doublets_view():
    """Rendered as it is (its own <default>s), street.xml frames the experiment's doublet view, rolled."""
    import xml.etree.ElementTree as ET

    defaults = {d.get("name"): d.get("value") for d in ET.parse(SCENE).getroot().iter("default")}
    expected = NARROW.params(
        float(defaults["fov"]), int(defaults["width"]), int(defaults["height"]), int(defaults["spp"])
    )
    assert defaults == expected and NARROW.roll_deg != 0


def test_framings_by_lens_and_by_field(doublet, triplet):
    assert framing(doublet) is FRAMINGS["solas-doublet"] is NARROW
    assert framing(triplet) is FRAMINGS["cooke-triplet"] is WIDE
    assert framing(SimpleNamespace(name="unknown", field_deg=3.0)) is NARROW
    assert framing(SimpleNamespace(name="unknown", field_deg=30.0)) is WIDE


def test_the_doublets_ideal_view_has_edges_in_every_annulus(doublet, tmp_path):
    """At the experiment's full size (4 spp: a few seconds), the spec's filters keep ≥ 20 edges per annulus."""
    from solas_mi.metrics.nssfr import natural_scene_sfr
    from solas_mi.render.stock import render_scene
    from solas_mi.render.user_scene import load

    xml = experiment_scene(SCENE, tmp_path, 531.0)
    scene = load(xml, "llvm_ad_spectral", None, framing(doublet).params(4.0, 1280, 960, 4))
    image = render_scene(scene, 4).image[..., 0] / 3.0
    report = natural_scene_sfr(image, full_scale=None)
    counts = [s.count for s in report.before]
    assert min(counts) >= 20, counts
    # the film's Gaussian filter (σ = 0.5 px) alone: MTF50 = √(ln 2 / (2π² σ²)) = 0.375 cy/px
    assert all(0.3 < s.mean_mtf50 < 0.42 for s in report.before)


def test_the_experiment_end_to_end(tmp_path):
    out = tmp_path / "street"
    assert (
        main(
            [
                "experiment",
                "street",
                "-o",
                str(out),
                "--size",
                "160x120",
                "--spp",
                "16",
                "--spp-ideal",
                "4",
                "--variant",
                "llvm_ad_spectral",
                "--depth-layers",
                "1,2",
            ]
        )
        == 0
    )
    for name in (
        "street.md",
        "street.csv",
        "street.json",
        "ideal.exr",
        "depth.exr",
        "interp_32x24.exr",
        "patch_8x6.exr",
        "patch_32x24.exr",
        "render_infinity.exr",
        "render_20_m.exr",
        "fig5_interp_32x24.png",
        "error_interp_32x24_vs_render_20_m.png",
        "interp_32x24_at_140_m.exr",
    ):
        assert (out / name).is_file(), name
    report = strict_loads((out / "street.json").read_text())
    assert {r["image"] for r in report["sfr"]} == {
        "interp 32x24",
        "patch 8x6",
        "patch 32x24",
        "render infinity",
        "render 20 m",
        "interp 32x24 at 140 m",
        "depth-aware interp 16x12, 3 nodes, focus infinity",
        "depth-aware interp 16x12, 3 nodes, focus 20 m",
    }
    assert set(report["seconds"]) >= {"(a) ideal image", "(c) lens render, focus at 20 m"}
    infinity, near = (report["errors"][f"interp 32x24 vs render {f}"] for f in ("infinity", "20 m"))
    assert near["rel_rmse_near"] < near["rel_rmse_far"]  # focused at 20 m: the near post sharp, the far field not
    # the convolution (objects at infinity) fits the near post better when the lens is focused on it, and the
    # far field better when it is focused at infinity
    assert near["rel_rmse_near"] < infinity["rel_rmse_near"] and infinity["rel_rmse_far"] < near["rel_rmse_far"]
    # (g) focused at 20 m, the depth-aware convolution (PSFs of the refocused lens per depth) fits the far field
    # far better than the single grid of the lens focused as its file says, and as well as the near objects
    depth = report["errors"]["depth-aware interp 16x12, 3 nodes, focus 20 m vs render 20 m"]
    assert depth["rel_rmse_far"] < 0.5 * near["rel_rmse_far"]
    assert {e["nodes"] for n, e in report["errors"].items() if n.startswith("depth-aware")} == {1, 2, 3}
    assert "render noise removed" in (out / "street.md").read_text()
    assert not list(out.glob(".*"))  # no temporary file left
    # every name plain (the depth-aware images are named "…, 3 nodes, focus 20 m": no comma, no space)
    assert [p.name for p in out.rglob("*") if safe_name(p.name) != p.name] == []
    assert (out / "depth-aware_interp_16x12_3_nodes_focus_20_m.exr").is_file()


def test_bad_settings(tmp_path, doublet):
    with pytest.raises(SolasError, match="spp lens 0 must be a positive integer"):
        Settings(spp_lens=0).check()
    with pytest.raises(SolasError, match="near focus -1"):
        Settings(near_focus_m=-1.0).check()
    with pytest.raises(SolasError, match="no street scene"):
        run(doublet, tmp_path, Settings(width=64, height=48, scene=tmp_path / "none.xml"))


def test_a_street_too_large_is_refused_before_its_folder_is_made(tmp_path, capsys):
    from solas_mi.cli import main

    out = tmp_path / "street"
    assert main(["experiment", "street", "-o", str(out), "--size", "100000x100000", "--spp", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--force" in err, err
    assert not out.exists()  # nothing made for a run that never started


def test_a_fisheye_is_refused_naming_why_and_what_to_do_instead(tmp_path, capsys):
    """The experiment's ideal image is a pinhole camera's of the lens's field: a fisheye's ±90 deg is
    refused in one line that names the fisheye and the commands that render one, before any folder."""
    from solas_mi.cli import main

    out = tmp_path / "street"
    assert (
        main(
            [
                "experiment",
                "street",
                "--lens",
                "nikkor-fisheye",
                "-o",
                str(out),
                "--size",
                "64x48",
                "--spp",
                "4",
                "--spp-ideal",
                "4",
                "--depth-layers",
                "none",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "fisheye" in err and "pinhole" in err and "render-image" in err, err
    assert not out.exists()
