"""The fixture of the analysis tests: the Cooke triplet (the lenses with closed forms: `ideal_lenses`)."""

import pytest

from solas_mi.optics.lens import Lens


@pytest.fixture(scope="module")
def cooke():
    return Lens.load("cooke-triplet")
