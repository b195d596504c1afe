"""Mitsuba set-up (`render.mitsuba`): variants and the plugins registered for them."""

import pytest

from solas_mi import SolasError
from solas_mi.render.mitsuba import mitsuba


def test_unknown_variant():
    with pytest.raises(SolasError, match="variant"):
        mitsuba("llvm_ad_rgb_nonexistent")


def test_a_variant_change_registers_the_plugins_again():
    """The plugin classes subclass the current variant's types, so each variant gets its own."""
    for variant in ("scalar_spectral", "llvm_ad_spectral"):
        mi = mitsuba(variant)
        assert isinstance(mi.load_dict({"type": "sellmeier_dielectric"}), mi.BSDF)
