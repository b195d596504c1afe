"""The shipped lenses written from published prescriptions: first-order data against the published
values, their field reachable by real chief rays, and their files read back through every format."""

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.optics.paraxial import paraxial
from solas_mi.optics.pupil import chief_rays

# name: (published EFL mm, published f/#, half field deg) — see each lens file's header for the source
PUBLISHED = {
    "double-gauss-50mm": (50.0, 2.0, 22.0),
    "wide-angle-22mm": (22.0, 2.68, 44.0),  # f/# with the table's stop (the source states none)
}


# The published tables (radius, thickness to the next surface, aperture diameter; mm; stop radius 0;
# the last thickness is the focus, not tabulated) and their indices n_d.
TABLES = {
    "double-gauss-50mm": (
        [
            (29.475, 3.76, 25.2),
            (84.83, 0.12, 25.2),
            (19.275, 4.025, 23.0),
            (40.77, 3.275, 23.0),
            (12.75, 5.705, 18.0),
            (0.0, 4.5, None),
            (-14.495, 1.18, 17.0),
            (40.77, 6.065, 20.0),
            (-20.385, 0.19, 20.0),
            (437.065, 3.22, 20.0),
            (-39.73, None, 20.0),
        ],
        [1.670, 1, 1.670, 1.699, 1, 1, 1.603, 1.658, 1, 1.717, 1],
    ),
    "wide-angle-22mm": (
        [
            (35.98738, 1.21638, 23.716),
            (11.69718, 9.99570, 17.996),
            (13.08714, 5.12622, 12.364),
            (-22.63294, 1.76924, 9.812),
            (71.05802, 0.81840, 9.152),
            (0.0, 2.27766, 8.756),
            (-9.58584, 2.43254, 8.184),
            (-11.28864, 0.11506, 9.152),
            (-166.7765, 3.09606, 10.648),
            (-7.59110, 1.32682, 11.440),
            (-16.76620, 3.98068, 12.276),
            (-7.70286, 1.21638, 13.420),
            (-11.97328, None, 17.996),
        ],
        [1.540, 1, 1.772, 1.617, 1, 1, 1.617, 1, 1.713, 1.805, 1, 1.617, 1],
    ),
}


@pytest.mark.parametrize("name", sorted(TABLES))
def test_the_file_is_the_published_table_scaled(name):
    """Every tabulated length of the file is the published one times one factor (within 1e-6, the
    file's rounding), that factor is within 1 % of 1, and the indices at the d line are the table's."""
    rows, nd = TABLES[name]
    lens = Lens.load(name)
    scale = lens.surfaces[0].radius / rows[0][0]
    assert scale == pytest.approx(1.0, abs=0.01)
    for s, row in zip(lens.surfaces, rows, strict=True):
        for value, published in zip((s.radius, s.thickness, s.diameter), row):
            if published is not None:
                assert value == pytest.approx(scale * published, rel=1e-6, abs=1e-6)
    assert lens.indices(587.5618)[1:] == pytest.approx(nd, abs=5e-5)


@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_efl_and_f_number_match_the_published_values(name):
    efl, fno, field = PUBLISHED[name]
    lens = Lens.load(name)
    p = paraxial(lens, 587.5618)
    assert p.efl_mm == pytest.approx(efl, rel=1e-3)
    assert p.f_number == pytest.approx(fno, rel=1e-2)
    assert p.image_offset_mm == pytest.approx(0.0, abs=1e-3)  # image plane at the paraxial focus
    assert lens.field_deg == field


@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_the_whole_field_is_imaged(name):
    """Real chief rays reach the image across the field, and the image height grows with the angle."""
    lens = Lens.load(name)
    angles = np.linspace(0.0, lens.field_deg, 6)
    heights = chief_rays(lens, np.stack([0 * angles, angles], -1), np.full(6, 587.5618)).image_xy[:, 1]
    assert np.all(np.isfinite(heights)) and np.all(np.diff(heights) > 0)
    assert heights[-1] < lens.image_diameter / 2


def test_the_double_gauss_glass_is_resolved_as_its_file_says():
    lens = Lens.load("double-gauss-50mm")
    assert [s.glass.name for s in lens.surfaces if s.glass.kind != "air"] == [
        "SCHOTT:N-BAF10",
        "SCHOTT:N-BAF10",
        "model:1.699/30.1",
        "model:1.603/38",
        "model:1.658/57.3",
        "model:1.717/48",
    ]
