"""The `sfr`, `ss-sfr` and `sfr-target` commands."""

import pytest
from strict_json import strict_loads

from solas_mi.cli import main
from solas_mi.imageio import write_exr
from solas_mi.metrics.targets import analytic_mtf50


def run_json(capsys, *argv):
    code = main(list(argv))
    return code, strict_loads(capsys.readouterr().out)


def test_target_png_then_auto_sfr(tmp_path, capsys):
    out = tmp_path / "edge.png"
    assert main(["sfr-target", "-o", str(out), "--angle-deg", "5", "--sigma-px", "1"]) == 0
    assert "0.179965" in capsys.readouterr().out
    assert [p.name for p in tmp_path.iterdir()] == ["edge.png"]
    code, data = run_json(capsys, "sfr", str(out), "--json")
    assert code == 0 and data["rois_from"] == "auto" and len(data["results"]) == 1
    res = data["results"][0]
    assert res["valid"] and res["angle_deg"] == pytest.approx(5.0, abs=0.1)
    assert res["mtf50"] == pytest.approx(0.179965, rel=0.015)  # 8-bit sRGB quantisation
    assert len(res["freq_cy_px"]) == len(res["sfr"])


def test_square_chart_exr_gives_four_edges(tmp_path, capsys):
    out = tmp_path / "square.exr"
    assert (
        main(
            [
                "sfr-target",
                "-o",
                str(out),
                "--shape",
                "square",
                "--size",
                "256x256",
                "--angle-deg",
                "6",
                "--sigma-px",
                "1.5",
            ]
        )
        == 0
    )
    capsys.readouterr()
    code, data = run_json(capsys, "sfr", str(out), "--json", "--mode", "2017")
    assert code == 0 and len(data["results"]) == 4
    assert sorted(r["orientation"] for r in data["results"]) == ["horizontal"] * 2 + ["vertical"] * 2
    for r in data["results"]:
        assert r["valid"] and r["mode"] == "2017"
        assert r["mtf50"] == pytest.approx(analytic_mtf50(1.5, 6.0), rel=0.01)


def test_sfr_with_roi_text_and_invalid_edge(tmp_path, capsys):
    out = tmp_path / "flat.png"
    main(["sfr-target", "-o", str(out), "--angle-deg", "0"])
    capsys.readouterr()
    assert main(["sfr", str(out), "--roi", "20,10,90,100"]) == 1
    text = capsys.readouterr().out
    assert "invalid" in text and "0°" in text


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--roi", "1,2,3"], "malformed"),
        (["--roi", "100,100,64,64"], "leaves"),
        (["--full-scale", "-1"], "full-scale"),
    ],
)
def test_sfr_user_errors_exit_2(tmp_path, capsys, argv, message):
    out = tmp_path / "edge.png"
    main(["sfr-target", "-o", str(out)])
    assert main(["sfr", str(out), *argv]) == 2
    assert message in capsys.readouterr().err


def test_target_user_errors_exit_2(tmp_path, capsys):
    assert main(["sfr-target", "-o", str(tmp_path / "edge.jpg")]) == 2
    assert main(["sfr-target", "-o", str(tmp_path / "edge.png"), "--size", "12x"]) == 2
    assert "--size '12x' must look like 32x24" in capsys.readouterr().err
    assert main(["sfr", str(tmp_path / "missing.png")]) == 2
    assert list(tmp_path.iterdir()) == []


def test_ss_sfr_compare_json_and_plot(tmp_path, capsys, graded_scene):
    a, b, plot = tmp_path / "a.exr", tmp_path / "b.exr", tmp_path / "fig.png"
    write_exr(a, {"Y": graded_scene()})
    write_exr(b, {"Y": graded_scene((1.0, 1.4, 1.8))})
    code, data = run_json(
        capsys, "ss-sfr", str(a), "--compare", str(b), "--json", "--plot", str(plot), "--full-scale", "1"
    )
    assert code == 0 and plot.is_file()
    assert [s["name"] for s in data["annuli"]] == ["centre", "middle", "edge"]
    assert all(s["count"] >= 4 for s in data["annuli"])
    change = data["mean_change_mtf50"]
    assert change[0] == pytest.approx(0.0, abs=1e-12) and change[1] < 0 and change[2] < 0
    ratio = [post["mean_mtf50"] / pre["mean_mtf50"] for pre, post in zip(data["annuli"], data["annuli_after"])]
    assert ratio[2] < ratio[1] < ratio[0]
    assert all("mtf50_after" in r for r in data["rois"])
    assert main(["ss-sfr", str(a), "--annuli", "equal-area"]) == 0
    assert "| centre | 0.00–0.58 |" in capsys.readouterr().out


@pytest.mark.parametrize("suffix", ["png", "exr"])
def test_a_colour_channel_of_a_grey_image_is_refused(tmp_path, capsys, suffix):
    """`sfr --channel R` of a grey image measured its grey values and said nothing."""
    out = tmp_path / f"edge.{suffix}"
    assert main(["sfr-target", "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["sfr", str(out), "--channel", "R"]) == 2
    err = capsys.readouterr().err
    assert f"--channel R: {out} is a grey image (one channel)" in err and err.count("\n") == 1, err


def test_a_negative_noise_seed_is_one_line(tmp_path, capsys):
    """`sfr-target --seed=-1` was a traceback from NumPy."""
    out = tmp_path / "edge.png"
    assert main(["sfr-target", "-o", str(out), "--noise", "0.05", "--seed=-1"]) == 2
    err = capsys.readouterr().err
    assert "noise seed -1 must be a whole number ≥ 0" in err and err.count("\n") == 1, err
    assert not out.exists()
