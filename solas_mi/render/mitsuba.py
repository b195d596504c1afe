"""Mitsuba for solas-mi: the variant, the plugins registered for it, and loading a scene file.

Variants (float32): spectral — `llvm_ad_spectral` by default, `cuda_ad_spectral` where a CUDA device
works, `scalar_spectral` for small reference renders — and, on request, mono — `llvm_ad_mono`,
`cuda_ad_mono` — for a job of one wavelength (`variant_for`: why mono is not the default). The
solas-mi plugins (`plugins/`, installed as `solas_mi.plugins`) are registered once for each variant,
whoever set it.

A mono variant carries no wavelength: the plugins take the response's one wavelength instead (the
lens sensors trace the lens at it, `sellmeier_dielectric` and `image_object` their `wavelength`
parameter, written by `scene`), and Mitsuba's own plugins turn RGB and spectral data into luminance.
Mono therefore equals spectral at λ only where the scene's spectra are grey (flat): the image-object
scene (its emitter picks the image channel of λ's band) and scenes of grey data, e.g. the street
experiment. RGB variants are refused: the lens needs a wavelength.

    mi = solas_mi.mitsuba()                      # the variant set, the plugins registered
    scene = mi.load_file("scenes/solas_doublet/scene.xml")
    image = mi.render(scene)                     # Mitsuba's path integrator, through the lens
"""

from __future__ import annotations

from pathlib import Path

from ..errors import SolasError, plugin_error
from ..llvm import select_libllvm

VARIANTS = ("llvm_ad_spectral", "scalar_spectral", "cuda_ad_spectral", "llvm_ad_mono", "cuda_ad_mono")
SCENE_SUFFIXES = (".xml",)  # Mitsuba scene files (a batch's render items, `camera`'s scene input)
_registered: set[str] = set()  # variants whose plugin classes are registered


def default_variant() -> str:
    """cuda_ad_spectral where a CUDA device works, else llvm_ad_spectral."""
    select_libllvm()
    import drjit as dr

    return "cuda_ad_spectral" if dr.has_backend(dr.JitBackend.CUDA) else "llvm_ad_spectral"


def spectral(variant: str) -> bool:
    """Whether `variant` carries wavelengths (a spectral variant)."""
    return "spectral" in variant


def check_variant(variant: str, response) -> None:
    """SolasError unless `variant` is a known one that can render `response`
    (`render.response.Response`): a non-spectral variant needs a response of one wavelength."""
    check_name(variant)
    if not spectral(variant) and response.single_wavelength is None:
        raise SolasError(
            f"Mitsuba variant {variant} is not spectral: it renders one wavelength, and camera response "
            f"{response.name} has more (use a spectral variant, or a response mono:<nm>)"
        )


def variant_for(response, variant: str | None = None) -> str:
    """The Mitsuba variant of a job at camera response `response` (`render.response.Response`):
    `variant` when given (the user's --variant, checked by `check_variant`), else the spectral JIT
    variant (`default_variant`), also at one wavelength. The mono variant is measured no faster there
    (`benchmarks/bench_mono.py`, README): solas-mi's loop uses one lane of the spectral variant's four
    and takes the same CPU time in mono, and Mitsuba's integrators render the street scene 1.5× slower
    in mono (its hdrfilm costs more than the spectral variant's one-channel specfilm). A mono variant
    renders the same image at λ where the scene's spectra are grey (the image-object scene, the
    street experiment); elsewhere it turns RGB and spectral data into luminance."""
    if variant is None:
        return default_variant()
    check_variant(variant, response)
    return variant


def check_name(variant: str) -> None:
    """SolasError unless `variant` is one of VARIANTS (an RGB variant named as such)."""
    if variant not in VARIANTS:
        why = " (RGB variants cannot trace the lens: it needs a wavelength)" if "rgb" in str(variant) else ""
        raise SolasError(f"variant {variant!r} must be one of {', '.join(VARIANTS)}{why}")


def mitsuba(variant: str | None = None):
    """Mitsuba with a variant set and the solas-mi plugins registered for it.

    The entry for Python users: after it, a scene file or a `mi.load_dict` dictionary can name the
    plugins (``lens_camera``, ``lens_sensor``, ``sellmeier_dielectric``, ``coated_dielectric``,
    ``image_object``; the
    [plugin reference](plugins.md)) like Mitsuba's own.

    Parameters
    ----------
    variant : str, optional
        The Mitsuba variant, one of `VARIANTS`; default: `default_variant()` (``cuda_ad_spectral``
        where a GPU works, else ``llvm_ad_spectral``).

    Returns
    -------
    module
        The `mitsuba` module, its variant set.

    Raises
    ------
    SolasError
        For a variant not in `VARIANTS` or not in this Mitsuba build, or one that cannot start (a CUDA
        variant without a working device).

    Examples
    --------
    >>> import solas_mi
    >>> mi = solas_mi.mitsuba("scalar_spectral")
    >>> mi.variant()
    'scalar_spectral'
    """
    variant = variant or default_variant()
    check_name(variant)
    select_libllvm()
    import mitsuba as mi

    if variant not in mi.variants():
        raise SolasError(f"variant {variant} is not in this Mitsuba build (has: {', '.join(mi.variants())})")
    if mi.variant() != variant:
        try:
            mi.set_variant(variant)
        except Exception as exc:  # a CUDA variant without a working device
            raise SolasError(f"Mitsuba variant {variant} cannot start: {exc}") from exc
    if variant not in _registered:
        from .. import plugins

        plugins.register()
        _registered.add(variant)
    return mi


def load_scene(path: str | Path, variant: str | None = None, **params):
    """Load a scene XML (lengths in mm) with the solas-mi plugins; `params` fill its <default> values.

    Loaded on the calling thread (`parallel=False`): the plugins trace the lens with Dr.Jit when they
    are built (exit-pupil bounds, image scales), and built on Mitsuba's loader threads one such trace
    crashed the process (a segmentation fault in `tracer.trace` under `lens_sensor`, seen once in a
    full test run). The scenes' own meshes are few, so the parallel build saves little."""
    mi = mitsuba(variant)
    try:
        return mi.load_file(str(path), parallel=False, **{k: str(v) for k, v in params.items()})
    except RuntimeError as exc:
        raise plugin_error(exc, f"cannot load scene {path}") from None


MAX_SEED = 2**32 - 1  # Mitsuba's samplers take 32-bit seeds


def check_run(spp, seed) -> None:
    """Refuse what a render cannot use: `spp` must be a positive integer (samples per pixel), `seed`
    an integer from 0 to 2³² − 1."""
    if not (isinstance(spp, int) and not isinstance(spp, bool) and spp >= 1):
        raise SolasError(f"samples per pixel {spp!r} must be a positive integer")
    if not (isinstance(seed, int) and not isinstance(seed, bool) and 0 <= seed <= MAX_SEED):
        raise SolasError(f"seed {seed!r} must be an integer from 0 to {MAX_SEED}")


def pass_seed(seed: int, k: int) -> int:
    """The 32-bit seed of pass `k` of a render seeded with `seed`: distinct per pass and per seed."""
    return (seed * 1_000_003 + k) & 0xFFFFFFFF
