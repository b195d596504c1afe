"""Wide lenses at every field they image, whatever field their file states: a pbrt-style table of the
shipped fisheye (no field, no dispersion) and the fisheye stating a 50° field are aimed by continuation
where the paraxial guess loses the ray; their chief rays agree with the polar-field lens's (another
launch, another aim) on the y axis, where both field forms name the same direction."""

from dataclasses import replace

import numpy as np
import pytest

from solas_mi import Lens, SolasError
from solas_mi.optics import pupil as P
from solas_mi.optics.fields import ANGLE, POLAR

LINE_D = 587.5618


@pytest.fixture(scope="module")
def fisheye():
    return Lens.load("nikkor-fisheye")


@pytest.fixture(scope="module")
def table(fisheye, tmp_path_factory):
    """The fisheye as pbrt ships its lenses: four columns (radius, thickness, n_d, aperture), no field,
    no V_d; n_d is the catalogue glass's index at the d line, so the d-line traces are the same lens."""
    rows = [
        f"{s.radius!r} {s.thickness!r} {s.glass.index(LINE_D) if s.glass.kind != 'air' else 1.0!r} {s.diameter!r}"
        for s in fisheye.surfaces
    ]
    path = tmp_path_factory.mktemp("wide") / "fisheye.dat"
    path.write_text("# a fisheye table, pbrt style\n" + "\n".join(rows) + "\n")
    return Lens.load(path)


def _heights(lens, theta):
    fields = np.stack([np.zeros(len(theta)), theta], axis=-1)
    return P.chief_rays(lens, fields, np.full(len(theta), LINE_D))


def test_a_table_without_field_is_aimed_to_80_degrees(table, fisheye):
    assert table.field_deg == 0 and table.field_type is ANGLE and fisheye.field_type is POLAR
    theta = np.arange(0.0, 81.0, 10.0)
    mine, polar = _heights(table, theta), _heights(fisheye, theta)
    assert not mine.vignetted.any()
    # paraxial-guess failures at 60° and beyond were "the lens does not image that field"
    np.testing.assert_allclose(mine.image_xy, polar.image_xy, atol=1e-9)
    assert mine.image_xy[6, 1] == pytest.approx(10.369, abs=1e-3)  # 60°


def test_a_wide_lens_stating_a_small_field_images_past_it(fisheye):
    stated = replace(fisheye, field_deg=50.0)
    assert stated.field_type is ANGLE
    theta = np.array([0.0, 50.0, 70.0, 85.0])
    np.testing.assert_allclose(_heights(stated, theta).image_xy, _heights(fisheye, theta).image_xy, atol=1e-9)


def test_polar_continuation_follows_the_pupil_to_where_light_stops(fisheye):
    """The fixed 2° continuation lost the chief ray past 97°; light arrives to about 105° (the pupil
    function's transmission is still positive there) and no ray of 110° passes the stop."""
    chief = _heights(fisheye, np.array([97.0, 98.0, 100.0, 105.0]))
    h = chief.image_xy[:, 1]
    assert np.all(np.diff(h) > 0) and h[0] > 14.4 and h[-1] < 15.0
    pf = P.pupil_function(fisheye, [[0.0, 98.0], [0.0, 105.0]], [LINE_D, LINE_D], 32)
    assert np.all(pf.transmission > 0)
    with pytest.raises(SolasError, match="no real ray .* passes the stop .* does not image"):
        _heights(fisheye, np.array([110.0]))
    assert P.nearest_passing(fisheye, np.array([0.0, 110.0]), LINE_D) is None


def test_widest_field_of_a_lens_without_one(table, fisheye):
    assert P.widest_field(table, LINE_D) == pytest.approx(ANGLE.largest_deg)
    widest = P.widest_field(fisheye, LINE_D)  # the chief ray is clipped (vignetted) past about 98.4°
    assert 97.0 < widest < 102.0
    assert not _heights(fisheye, np.array([widest])).vignetted.any()


def test_lens_info_says_a_lens_has_no_dispersion(table, fisheye, capsys):
    from strict_json import strict_loads

    from solas_mi.cli import main

    assert not table.dispersive and fisheye.dispersive
    assert main(["lens", "info", table.source, "--fields", "0,60"]) == 0
    assert "no dispersion data" in capsys.readouterr().out
    assert main(["lens", "info", table.source, "--fields", "0,20", "--json"]) == 0
    assert strict_loads(capsys.readouterr().out)["dispersion"] is False
    assert main(["lens", "info", "nikkor-fisheye", "--fields", "0,20", "--json"]) == 0
    assert strict_loads(capsys.readouterr().out)["dispersion"] is True


@pytest.mark.slow
def test_check_stability_passes_on_a_table_without_field(table):
    """Was exit 1: a lens without a field had its cases run at 0° (the exit-pupil bound of a 0 mm film). Its
    apertures pass the chief ray of every field to 88.5°: it is checked at the paraxial field whose image
    height is its largest clear semi-diameter."""
    from solas_mi.optics.paraxial import paraxial
    from solas_mi.validation.stability import check_stability

    cases = check_stability(table)
    size = max(s.semi_diameter for s in table.surfaces)
    field = np.degrees(np.arctan(size / abs(paraxial(table, LINE_D).efl_mm)))
    assert cases[0].name.startswith("field of a lens that states none") and f"{field:.3f} deg" in cases[0].observed
    assert [c.name for c in cases if not c.passed] == []
