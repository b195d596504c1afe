"""The render tests' Mitsuba: `mi`, the `mitsuba` module in llvm_ad_spectral (tests/conftest.py's
`variant_llvm_ad_spectral`), for a test that renders in that variant; a test in another one requests
its own `variant_<name>` or `variants_spectral`."""

import pytest


@pytest.fixture
def mi(variant_llvm_ad_spectral):
    return variant_llvm_ad_spectral
