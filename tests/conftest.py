"""Fixtures shared by the test modules: the shipped lenses."""
import copy

import pytest
import tomllib

from solas_mi.resources import resource_dir


@pytest.fixture(scope="session")
def doublet():
    from solas_mi import Lens

    return Lens.load("solas-doublet")


@pytest.fixture(scope="session")
def triplet():
    from solas_mi import Lens

    return Lens.load("cooke-triplet")


@pytest.fixture
def doublet_spec():
    """The shipped doublet's lens-file dictionary, free to modify."""
    with open(resource_dir("scenes") / "lenses" / "solas_doublet.toml", "rb") as f:
        return copy.deepcopy(tomllib.load(f))
