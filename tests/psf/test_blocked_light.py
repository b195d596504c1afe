"""A field where the lens lets no light through: a clear error for one PSF or spot (never NaN or an
all-zero PSF that claims to sum to one), and dark nodes named in a grid's warnings."""

import pytest

from solas_mi import Lens, SolasError, spot
from solas_mi.psf import psf, psf_grid


@pytest.fixture
def pinhole_front(doublet_spec):
    """The doublet with a 2 mm front aperture: at 3.5° the whole beam misses it."""
    doublet_spec["surface"][0]["diameter"] = 2.0
    return Lens.from_dict(doublet_spec, source="pinhole-front")


@pytest.mark.parametrize(
    "call",
    [
        lambda lens: spot(lens, (0, 3.5), 531.0),
        lambda lens: psf(lens, (0, 3.5), 531.0),
        lambda lens: psf(lens, (0, 3.5), 531.0, method="geometric"),
    ],
)
def test_no_light_is_a_clear_error(pinhole_front, call):
    with pytest.raises(SolasError, match=r"\(0, 3\.5\) deg.*blocked"):
        call(pinhole_front)


def test_dark_grid_nodes_are_named(pinhole_front):
    g = psf_grid(
        pinhole_front, grid=(3, 3), field_range_deg=3.5, field_sampling="edges", size=32, wavelengths_nm=[531.0]
    )
    assert "8 of 9 PSFs receive no light" in " ".join(g.meta["warnings"])
    assert g.data[0, 1, 1].sum() == pytest.approx(1.0) and g.data[0, 0, 0].sum() == 0.0
