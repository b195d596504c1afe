"""Mitsuba for solas-mi: the variant, the plugins registered for it, and loading a scene file.

Variants are spectral (float32): `llvm_ad_spectral` by default, `cuda_ad_spectral` where a CUDA
device works, `scalar_spectral` for small reference renders. The solas-mi plugins (`plugins/`,
installed as `solas_mi.plugins`) are registered again whenever the variant changes.
"""
from __future__ import annotations

from ..errors import SolasError
from ..llvm import select_libllvm

VARIANTS = ("llvm_ad_spectral", "scalar_spectral", "cuda_ad_spectral")


def default_variant() -> str:
    """cuda_ad_spectral where a CUDA device works, else llvm_ad_spectral."""
    select_libllvm()
    import drjit as dr

    return "cuda_ad_spectral" if dr.has_backend(dr.JitBackend.CUDA) else "llvm_ad_spectral"


def mitsuba(variant: str | None = None):
    """Mitsuba with `variant` set (default: `default_variant`) and the solas-mi plugins registered."""
    variant = variant or default_variant()
    if variant not in VARIANTS:
        raise SolasError(f"variant {variant!r} must be one of {', '.join(VARIANTS)}")
    select_libllvm()
    import mitsuba as mi

    if variant not in mi.variants():
        raise SolasError(f"variant {variant} is not in this Mitsuba build (has: {', '.join(mi.variants())})")
    if mi.variant() != variant:
        try:
            mi.set_variant(variant)
        except Exception as exc:  # a CUDA variant without a working device
            raise SolasError(f"Mitsuba variant {variant} cannot start: {exc}") from exc
        from .. import plugins

        plugins.register()
    return mi


def load_scene(path: str, variant: str | None = None, **params):
    """Load a scene XML (lengths in mm) with the solas-mi plugins; `params` fill its <default> values."""
    mi = mitsuba(variant)
    try:
        return mi.load_file(str(path), **{k: str(v) for k, v in params.items()})
    except RuntimeError as exc:
        raise SolasError(f"cannot load scene {path}: {exc}") from None
