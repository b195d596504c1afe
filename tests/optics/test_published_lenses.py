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
        "SCHOTT:N-BAF10", "SCHOTT:N-BAF10", "model:1.699/30.1", "model:1.603/38", "model:1.658/57.3", "model:1.717/48"]
