"""`solas-mi lens info` (optics.commands)."""

import numpy as np
import pytest

# DESIGN.md: facts about the SOLAS doublet that independent tools agree on.


def test_cli_lens_info_json(capsys):
    from strict_json import strict_loads

    from solas_mi.cli import main

    assert main(["lens", "info", "solas-doublet", "--json"]) == 0
    info = strict_loads(capsys.readouterr().out)
    rows = {r["wavelength_nm"]: r for r in info["per_wavelength"]}
    assert rows[531.0]["efl_mm"] == pytest.approx(99.9468, abs=1e-3)
    assert rows[531.0]["real_chief_ray_image_height_mm"][1] == pytest.approx(3.4745, abs=1e-3)


@pytest.mark.parametrize("name", ["solas-doublet", "cooke-triplet"])
def test_lens_info_carries_distortion_and_illumination(name, capsys):
    """Both lenses are rectilinear; the table's heights are the real chief rays' and its distortion is
    their departure from EFL·tanθ; the illumination falls steadily off the axis."""
    import numpy as np
    from strict_json import strict_loads

    from solas_mi.cli import main

    assert main(["lens", "info", name, "--json"]) == 0
    info = strict_loads(capsys.readouterr().out)
    d = info["distortion"]
    assert d["projection"] == "rectilinear"
    theta = np.radians(d["field_deg"])
    efl = next(r for r in info["per_wavelength"] if r["wavelength_nm"] == d["wavelength_nm"])["efl_mm"]
    assert np.allclose(d["rectilinear_height_mm"], efl * np.tan(theta))
    h, rect = np.array(d["image_height_mm"]), np.array(d["rectilinear_height_mm"])
    assert np.allclose(d["distortion_percent"][1:], (h[1:] / rect[1:] - 1) * 100)
    assert h[-1] == pytest.approx(abs(info["per_wavelength"][0]["real_chief_ray_image_height_mm"][1]), rel=0.02)
    ri = np.array(d["relative_illumination"])
    assert ri[0] == pytest.approx(1.0) and np.all(np.diff(ri) < 0) and ri[-1] > 0.5
    assert main(["lens", "info", name]) == 0
    assert "closest projection: rectilinear" in capsys.readouterr().out


@pytest.mark.parametrize("projection", ["rectilinear", "equidistant", "equisolid", "stereographic"])
def test_projection_classifier_picks_the_generating_projection(projection):
    import numpy as np

    from solas_mi.optics.distortion import PROJECTIONS, closest_projection, fit_projections

    angles = np.linspace(0.0, 60.0, 13)
    heights = 8.0 * PROJECTIONS[projection](np.radians(angles))
    fits = fit_projections(angles, heights)
    assert closest_projection(fits) == projection
    focal, residual = fits[projection]
    assert focal == pytest.approx(8.0) and residual < 1e-12


def test_projection_fit_beyond_90_degrees_leaves_out_rectilinear():
    import numpy as np

    from solas_mi import SolasError
    from solas_mi.optics.distortion import PROJECTIONS, closest_projection, fit_projections

    angles = np.linspace(0.0, 100.0, 11)
    fits = fit_projections(angles, 5.0 * PROJECTIONS["equisolid"](np.radians(angles)))
    assert fits["rectilinear"][1] == np.inf and closest_projection(fits) == "equisolid"
    with pytest.raises(SolasError, match=r"projection fit needs field angles in \[0, 180\) deg, one at least nonzero"):
        fit_projections([0.0, 0.0], [0.0, 0.0])


def test_lens_info_of_a_lens_without_field_shows_the_axis_once(tmp_path, capsys):
    """A pbrt-style table states no field: `lens info` shows the chief ray on the axis once (not once per
    ± half field, nor at "-0 deg"); fields given on the command line stay as given, -0 reading 0."""
    from strict_json import strict_loads

    from solas_mi.cli import main

    path = tmp_path / "singlet.dat"
    path.write_text(
        "# a singlet behind its stop, pbrt style\n0.0 5.0 1.0 10.0\n60.0 8.0 1.5 20.0\n-240.0 100.0 1.0 20.0\n"
    )
    assert main(["lens", "info", str(path)]) == 0
    out = capsys.readouterr().out
    assert out.count("chief ray y at 0 deg, paraxial") == 1 and out.count("chief ray y at 0 deg, real") == 1
    assert "-0 deg" not in out
    assert main(["lens", "info", str(path), "--json"]) == 0
    rows = strict_loads(capsys.readouterr().out)["per_wavelength"]
    assert rows and all(r["fields_deg"] == [0.0] and len(r["real_chief_ray_image_height_mm"]) == 1 for r in rows)
    assert main(["lens", "info", str(path), "--fields=-0,5,5"]) == 0
    out = capsys.readouterr().out
    assert "-0 deg" not in out and out.count("chief ray y at 5 deg, real") == 2


def test_lens_info_says_why_the_illumination_is_undefined(monkeypatch, capsys):
    """Where no light reaches the image's centre E(θ)/E(0) is no number: the table shows '-' and the
    reason (it printed NaN), the JSON holds null, and the rest of the table stays."""
    from strict_json import strict_loads

    from solas_mi.cli import main
    from solas_mi.optics import illumination

    monkeypatch.setattr(illumination, "irradiance", lambda lens, xy, *a, **k: np.zeros(len(np.atleast_2d(xy))))
    assert main(["lens", "info", "solas-doublet"]) == 0
    out = capsys.readouterr().out
    assert "nan" not in out.lower() and "rel. illum. '-': lens solas-doublet: no light reaches the centre" in out
    assert main(["lens", "info", "solas-doublet", "--json"]) == 0
    table = strict_loads(capsys.readouterr().out)["distortion"]
    assert table["relative_illumination"] == [None] * len(table["field_deg"]) and table["image_height_mm"][-1] > 0


def test_lens_list_json_is_strict(capsys):
    from strict_json import strict_loads

    from solas_mi.cli import main
    from solas_mi.optics.lens import shipped_lenses

    assert main(["lens", "list", "--json"]) == 0
    rows = strict_loads(capsys.readouterr().out)
    assert [r["name"] for r in rows] == list(shipped_lenses())
    assert next(r for r in rows if r["name"] == "solas-doublet")["efl_mm"] == pytest.approx(99.95, abs=0.01)


TELECENTRIC = """name = "image-telecentric"
[[surface]]
radius = 0.0
thickness = 100.0
diameter = 10.0
material = "AIR"
stop = true
[[surface]]
radius = 50.0
thickness = 3.0
diameter = 20.0
material = "model:1.5"
[[surface]]
radius = 0.0
thickness = 100.0
diameter = 20.0
material = "AIR"
"""


def test_lens_info_json_of_an_image_telecentric_lens_is_strict(tmp_path, capsys):
    """The stop in the front focal plane (f = R/(n − 1) = 100 mm) puts the exit pupil at infinity: `lens
    info --json` wrote `Infinity`, which JSON.parse, Go and serde refuse; it writes "inf" (the table
    prints inf), which float() reads back as the infinity."""
    from strict_json import strict_loads

    from solas_mi.cli import main

    path = tmp_path / "telecentric.toml"
    path.write_text(TELECENTRIC)
    assert main(["lens", "info", str(path), "--json"]) == 0
    rows = strict_loads(capsys.readouterr().out)["per_wavelength"]
    for row in rows:
        assert row["exit_pupil_z_mm"] in ("inf", "-inf") and row["exit_pupil_diameter_mm"] in ("inf", "-inf")
        assert abs(float(row["exit_pupil_z_mm"])) == np.inf and row["exit_pupil_f_number"] == pytest.approx(10.0)
    assert main(["lens", "info", str(path)]) == 0
    assert "inf" in next(line for line in capsys.readouterr().out.splitlines() if line.startswith("exit pupil z"))


@pytest.mark.parametrize("flag", ["--wavelengths-nm", "--wavelengths", "--fields"])
@pytest.mark.parametrize("value", [",", " , ", ""])
def test_an_empty_list_is_an_error_naming_it(flag, value, capsys):
    """`lens info --wavelengths ,` printed a table of no wavelength (and `--fields ,` one of no field):
    an empty list is refused in one line naming the flag and the value."""
    from solas_mi.cli import main

    assert main(["lens", "info", "solas-doublet", flag, value]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and f"{value!r} must be one or more comma-separated numbers" in err, err
