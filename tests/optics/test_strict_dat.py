"""pbrt lens tables (.dat) read strictly: a row that cannot be a surface is an error naming its line,
never air or a glass without dispersion; a model glass written to .dat reads back as itself."""

import pytest

from solas_mi.errors import SolasError
from solas_mi.optics.glass import LINE_C, LINE_D, LINE_F
from solas_mi.optics.lens import Lens
from solas_mi.optics.paraxial import paraxial

TABLE = """# radius thickness n_d aperture V_d
50.0 5.0 {nd} 20.0 {vd}
-50.0 3.0 1.0 20.0 0
0 45.0 1.0 10.0 0
"""


@pytest.mark.parametrize(
    "nd, vd, message",
    [
        ("0.5", "60", "index 0.5 is neither air"),
        ("-1.5", "60", "index -1.5 is neither air"),
        ("1.5", "-60", "Abbe number -60 is negative"),
        ("nan", "60", "the index is nan"),
        ("1.5", "inf", "the Abbe number is inf"),
    ],
)
def test_a_row_that_cannot_be_a_surface_is_an_error_naming_its_line(tmp_path, nd, vd, message):
    path = tmp_path / "bad.dat"
    path.write_text(TABLE.format(nd=nd, vd=vd))
    with pytest.raises(SolasError, match=f"line 2: {message}"):
        Lens.load(path)


def test_a_model_glass_reads_back_as_itself(doublet_spec, tmp_path):
    doublet_spec["surface"][0]["material"] = "model:1.5168/64.17"  # N-BK7's catalogue n_d / V_d
    lens = Lens.from_dict(doublet_spec)
    back = Lens.load(lens.save(tmp_path / "model.dat"))
    assert back.surfaces[0].glass.name == "model:1.5168/64.17"
    for nm in (LINE_F, LINE_D, LINE_C):  # the .dat's wavelengths; the EFL of every one kept
        assert paraxial(back, nm).efl_mm == pytest.approx(paraxial(lens, nm).efl_mm, rel=1e-9)


def test_a_glass_comment_left_behind_by_an_edit_is_an_error(doublet_spec, tmp_path):
    doublet_spec["surface"][0]["material"] = "model:1.5168/64.17"
    path = Lens.from_dict(doublet_spec).save(tmp_path / "model.dat")
    path.write_text(path.read_text().replace(" 1.5168 ", " 1.6 "))
    with pytest.raises(SolasError, match="row 1: n_d 1.6 differs from its glass comment"):
        Lens.load(path)


@pytest.mark.parametrize("name", ["model:nan/64", "model:1.5/nan", "model : inf", "MODEL:abc/60"])
def test_a_model_glass_whose_numbers_do_not_read_is_named_as_a_model_glass(doublet_spec, name):
    """Not "unknown glass" with the catalogue's list: the model glass, and what its numbers must be."""
    doublet_spec["surface"][0]["material"] = name
    with pytest.raises(SolasError, match=r"model glass .* must read model:n_d/V_d") as info:
        Lens.from_dict(doublet_spec)
    assert "unknown glass" not in str(info.value)


def test_a_table_pbrt_cannot_trace_is_refused_naming_the_rows_and_the_step(tmp_path):
    """A biconvex singlet and a stop, written with the spacing column one row off (pbrt's unscaled
    dgauss.dat and telephoto.dat are so): the glass gets thickness 0, its faces cross, and pbrt's
    realistic camera, which steps only forward, cannot trace it (its writer refuses such a lens, so does
    ours): the table is refused naming rows 1 and 2 and the step, as the writer names them. The same rows
    with the column in place load."""
    right = "50.0 5.0 1.5 20.0\n-50.0 3.0 1.0 20.0\n0 45.0 1.0 10.0\n"
    shifted = "50.0 0.0 1.5 20.0\n-50.0 5.0 1.0 20.0\n0 3.0 1.0 10.0\n"
    (tmp_path / "right.dat").write_text(right)
    (tmp_path / "shifted.dat").write_text(shifted)
    assert not Lens.load(tmp_path / "right.dat").overlaps
    with pytest.raises(
        SolasError,
        match=r"shifted.dat: surfaces 1 \(row 1\) and 2 \(row 2\) (cross|overlap) .*\(thickness 0 "
        r"mm\); pbrt's realistic camera steps only forward.* damaged table",
    ):
        Lens.load(tmp_path / "shifted.dat")
