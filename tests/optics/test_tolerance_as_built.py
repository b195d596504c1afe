"""The tolerances of the lens as built (`optics.tolerance_placement`): a drawn decentre or tilt is the rigid
motion of its element that its deltas name (read back from the frames of the drawn lens, another route
than the breaks written), reproducible from (seed, index); the surfaces after it stay where designed; a bad
entry is refused by name."""

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.errors import SolasError
from solas_mi.optics import tolerance as tol
from solas_mi.optics.placement import Placement, frames

ELEMENT = [3, 4]  # the Cooke triplet's middle element


@pytest.fixture(scope="module")
def cooke():
    return Lens.load("cooke-triplet")


def _frames(lens):
    return frames(lens.surfaces, lens.image_placement)


def test_a_drawn_decentre_is_reproducible_and_is_the_placement_it_names(cooke):
    spec = tol.spec_from_dict(cooke, {"tolerance": [{"kind": "decentre", "surfaces": ELEMENT, "mm": 0.05}]})
    assert [t.name for t in spec.terms] == ["decentre_x s3-4", "decentre_y s3-4"]
    drawn, deltas = tol.draw(cooke, spec, 11, 4)
    again, same = tol.draw(cooke, spec, 11, 4)
    assert same == deltas == tol.draw_deltas(spec, 11, 4) and again == drawn
    assert deltas != tol.draw(cooke, spec, 11, 5)[1]
    assert drawn.surfaces[2].placement == Placement(decentre_x=deltas[0], decentre_y=deltas[1])
    moved = np.array([o1 - o0 for (o0, _), (o1, _) in zip(_frames(cooke), _frames(drawn))])
    expected = np.zeros_like(moved)
    expected[2:4, :2] = deltas  # the element's two vertices move by the decentre; nothing else moves
    assert np.abs(moved - expected).max() < 1e-12


def test_a_tilt_turns_its_element_about_its_first_vertex_and_leaves_the_rest(cooke):
    spec = tol.spec_from_dict(cooke, {"tolerance": [{"kind": "tilt", "surfaces": ELEMENT, "degrees": 0.3}]})
    drawn, (tx, ty) = tol.draw(cooke, spec, 3, 0)
    design, built = _frames(cooke), _frames(drawn)
    turn = Placement(tilt_x=tx, tilt_y=ty).rotation()
    pivot = design[2][0]
    for k in (2, 3):  # the element: turned about its first vertex
        assert np.abs(built[k][0] - (pivot + turn @ (design[k][0] - pivot))).max() < 1e-12
        assert np.abs(built[k][1] - turn).max() < 1e-12
    for k in (0, 1, 4, 5, 6):  # before, after and the image plane: as designed
        assert np.abs(built[k][0] - design[k][0]).max() < 1e-12 and np.abs(built[k][1] - np.eye(3)).max() < 1e-12


def test_the_paraxial_sensitivity_reads_each_as_built_term_back_from_the_frames(cooke):
    entries = [
        {"kind": "decentre", "surfaces": ELEMENT, "mm": 0.02},
        {"kind": "tilt", "surfaces": [5, 6], "degrees": 0.1, "distribution": "uniform"},
        {"kind": "sensor_tilt", "degrees": 0.2},
    ]
    spec = tol.spec_from_dict(cooke, {"tolerance": entries})
    rows = tol.paraxial_sensitivity(cooke, spec)
    assert [r["term"] for r in rows] == [t.name for t in spec.terms]
    for row, term in zip(rows, spec.terms):
        assert abs(row["parameter_plus"] - row["parameter_minus"] - 2 * term.value) < 1e-9 * term.value


@pytest.mark.parametrize(
    "entry, named",
    [
        ({"kind": "decentre", "surfaces": [3, 5], "mm": 0.01}, "consecutive"),
        ({"kind": "decentre", "surfaces": "all", "mm": 0.01}, "consecutive"),
        ({"kind": "tilt", "surfaces": [3, 4], "degrees": -0.1}, "degrees = -0.1"),
        ({"kind": "tilt", "surfaces": [3, 4], "mm": 0.1}, "degrees"),
        ({"kind": "sensor_tilt", "surfaces": [6], "degrees": 0.1}, "takes no surfaces"),
    ],
)
def test_a_bad_as_built_entry_is_refused_by_name(cooke, entry, named):
    with pytest.raises(SolasError, match=named):
        tol.spec_from_dict(cooke, {"tolerance": [entry]})


def test_elements_that_share_a_surface_are_refused(cooke):
    entries = [
        {"kind": "decentre", "surfaces": [3, 4], "mm": 0.01},
        {"kind": "tilt", "surfaces": [4, 5], "degrees": 0.1},
    ]
    with pytest.raises(SolasError, match="s3-4 and s4-5 share surfaces"):
        tol.spec_from_dict(cooke, {"tolerance": entries})


def test_the_last_elements_tilt_and_decentre_return_to_a_sensor_tilted_about_its_axial_point(cooke):
    entries = [
        {"kind": "decentre", "surfaces": [5, 6], "mm": 0.05},
        {"kind": "tilt", "surfaces": [5, 6], "degrees": 0.3},
        {"kind": "sensor_tilt", "degrees": 0.4},
    ]
    spec = tol.spec_from_dict(cooke, {"tolerance": entries})
    drawn, (dx, dy, tx, ty, sx, sy) = tol.draw(cooke, spec, 5, 2)
    design, built = _frames(cooke), _frames(drawn)
    turn = Placement(tilt_x=tx, tilt_y=ty).rotation()
    pivot = design[4][0] + np.array([dx, dy, 0.0])
    assert np.abs(built[5][0] - (pivot + turn @ (design[5][0] - design[4][0]))).max() < 1e-12
    assert np.abs(built[6][0] - design[6][0]).max() < 1e-12  # the image plane's axial point stays
    assert np.abs(built[6][1] - Placement(tilt_x=sx, tilt_y=sy).rotation()).max() < 1e-12
