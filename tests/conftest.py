"""Fixtures shared by the test modules.

- The shipped lenses: `doublet`, `triplet` (session), `doublet_spec` (its lens-file dictionary); a lens as built:
  `cooke_as_built` (its maker: the triplet with a decentred and tilted element, a toroid, a tilted sensor);
  `every_lens`: two shipped lenses and that one, each stage's tests on lenses with and without symmetry.
- Mitsuba variants, after Mitsuba's own `src/conftest.py`: `variant_<name>` for each of
  `render.mitsuba.VARIANTS` (e.g. `variant_llvm_ad_spectral`, `variant_scalar_spectral`,
  `variant_llvm_ad_mono`) sets that variant through `render.mitsuba.mitsuba` (so solas-mi's plugins
  are registered for it) and gives the `mitsuba` module; `variants_spectral` runs a test once in each
  spectral variant of this machine (llvm_ad_spectral, scalar_spectral). `in_variant` is the same as a
  context manager, for fixtures of a wider scope. The variant is process-wide state: every test finds
  again after it the variant it started with (`_keep_the_mitsuba_variant`, also for tests that switch
  it through the API, e.g. `render_image(variant=...)`; only the first variant ever set stays, Mitsuba
  having no way to unset it). A CUDA variant without a device is skipped.
- Synthetic PSF grids without the tracer: `synthetic_grid` (`SyntheticGrids`).
- solas-mi's caches (`solas_mi.caches.cache_root`: PSF grids, fitted cameras) in a folder of the session,
  never the user's (`_session_cache`, through $SOLAS_MI_CACHE_DIR, which commands run as subprocesses
  inherit); `fresh_cache` gives a test its own empty one (a test that counts what is computed).
"""

import contextlib
import copy
import math
import sys
import tomllib

import numpy as np
import pytest

from solas_mi.render.mitsuba import VARIANTS
from solas_mi.resources import resource_dir


@pytest.fixture(scope="session")
def doublet():
    from solas_mi import Lens

    return Lens.load("solas-doublet")


@pytest.fixture(scope="session")
def triplet():
    from solas_mi import Lens

    return Lens.load("cooke-triplet")


def _cooke_as_built(toroid: bool = True, sensor_tilt_deg: float = 0.0):
    """The Cooke triplet as built that the benchmarks time and compare with optiland (`benchmarks/as_built_lens.py`:
    its middle element decentred and tilted, with `toroid` a toroid last), with a sensor tilted about x by
    `sensor_tilt_deg`."""
    from dataclasses import replace
    from pathlib import Path

    from solas_mi.optics.placement import Placement

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    from as_built_lens import cooke_as_built

    image = Placement(tilt_x=sensor_tilt_deg) if sensor_tilt_deg else None
    return replace(cooke_as_built(toroid), image_placement=image)


@pytest.fixture(scope="session")
def cooke_as_built():
    """`_cooke_as_built`, the maker of the Cooke triplet as built."""
    return _cooke_as_built


AS_BUILT_LENS = "cooke-triplet-as-built"  # `every_lens`'s name of `_cooke_as_built(True, 0.5)`
EVERY_LENS = ("solas-doublet", "cooke-triplet", AS_BUILT_LENS)


@pytest.fixture(scope="session", params=EVERY_LENS)
def every_lens(request):
    """Each of two shipped lenses on one axis and the Cooke triplet as built (a decentred and tilted element, a
    toroid, the sensor tilted 0.5 deg), for the tests a stage runs on any lens."""
    from solas_mi import Lens

    return _cooke_as_built(True, 0.5) if request.param == AS_BUILT_LENS else Lens.load(request.param)


@pytest.fixture
def doublet_spec():
    """The shipped doublet's lens-file dictionary, free to modify."""
    with open(resource_dir("scenes") / "lenses" / "solas_doublet.toml", "rb") as f:
        return copy.deepcopy(tomllib.load(f))


@pytest.fixture(scope="session", autouse=True)
def _session_cache(tmp_path_factory):
    from solas_mi.caches import ENV

    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(ENV, str(tmp_path_factory.mktemp("solas-mi-cache")))
        yield


@pytest.fixture
def fresh_cache(tmp_path, monkeypatch):
    """An empty cache folder of solas-mi's for this test (set as $SOLAS_MI_CACHE_DIR)."""
    from solas_mi.caches import ENV

    folder = tmp_path / "solas-mi-cache"
    monkeypatch.setenv(ENV, str(folder))
    return folder


# ---------------------------------------------------------------------------------------- Mitsuba variants

SPECTRAL_VARIANTS = ("llvm_ad_spectral", "scalar_spectral")  # the spectral variants every build has


def current_variant() -> str | None:
    """Mitsuba's variant now, None while Mitsuba is not imported or no variant is set (this does not
    import Mitsuba)."""
    mi = sys.modules.get("mitsuba")
    return mi.variant() if mi is not None else None


def restore_variant(previous: str | None) -> None:
    """Set `previous` again (with its plugins registered) where the variant has changed since."""
    if previous is None or current_variant() == previous:
        return
    if previous in VARIANTS:
        from solas_mi.render.mitsuba import mitsuba

        mitsuba(previous)
    else:  # a variant solas-mi does not use, set by Mitsuba itself
        sys.modules["mitsuba"].set_variant(previous)


@contextlib.contextmanager
def in_variant(variant: str):
    """The `mitsuba` module with `variant` set through `render.mitsuba.mitsuba` (solas-mi's plugins
    registered for it); the variant before comes back on exit. A CUDA variant that cannot start skips."""
    from solas_mi import SolasError
    from solas_mi.render.mitsuba import mitsuba

    previous = current_variant()
    try:
        try:
            mi = mitsuba(variant)
        except SolasError as exc:
            if variant.startswith("cuda"):
                pytest.skip(f"Mitsuba variant {variant} is not available here: {exc}")
            raise
        yield mi
    finally:
        restore_variant(previous)


@pytest.fixture(autouse=True)
def _keep_the_mitsuba_variant():
    """Whatever a test does to the process-wide variant, the next test finds the one it found."""
    previous = current_variant()
    yield
    restore_variant(previous)


@pytest.fixture(name="in_variant", scope="session")
def in_variant_fixture():
    """`in_variant` (a context manager) for fixtures of module or session scope, which cannot request
    the function-scoped `variant_<name>` fixtures."""
    return in_variant


def _variant_fixture(variant: str):
    @pytest.fixture(name=f"variant_{variant}")
    def fixture():
        with in_variant(variant) as mi:
            yield mi

    fixture.__doc__ = f"The `mitsuba` module in {variant}, the variant before restored after the test."
    return fixture


for _variant in VARIANTS:
    globals()[f"_variant_{_variant}"] = _variant_fixture(_variant)


@pytest.fixture(params=SPECTRAL_VARIANTS)
def variants_spectral(request):
    """The `mitsuba` module in each spectral variant in turn (its name: `mi.variant()`)."""
    with in_variant(request.param) as mi:
        yield mi


# --------------------------------------------------------------------------------------- synthetic grids


class SyntheticGrids:
    """PSF grids without the tracer, on a pinhole camera of focal length `focal_mm` (mm): the chief ray
    of each node is its ideal image point (plus optional offsets), fields in degrees, pitch in µm.

        grid = synthetic_grid((3, 4, 4), size=31, pitch_um=2.0, sigma_um=8.0)   # Gaussians everywhere
        grid = synthetic_grid.from_psfs(psfs, pitch_um, offsets_um)            # PSFs of your own
    """

    focal_mm = 100.0
    KINDS = ("gaussian", "delta")

    @staticmethod
    def gaussian(size: int, sigma_um: float, pitch_um: float) -> np.ndarray:
        """A centred round Gaussian of σ `sigma_um` on `size`² samples of `pitch_um`, summing to 1."""
        x = (np.arange(size) - size // 2) * pitch_um
        g = np.exp(-0.5 * (x[None, :] ** 2 + x[:, None] ** 2) / sigma_um**2)
        return g / g.sum()

    @staticmethod
    def delta(size: int) -> np.ndarray:
        """All the light in the centre sample of `size`² samples."""
        d = np.zeros((size, size))
        d[size // 2, size // 2] = 1.0
        return d

    @classmethod
    def pixel_um(cls, width: int, fov: float = 2.0) -> float:
        """The pixel (µm) of an image `width` px wide spanning ±`fov`° on the pinhole camera."""
        return 2e3 * cls.focal_mm * math.tan(math.radians(fov)) / width

    @classmethod
    def from_psfs(
        cls,
        psfs,
        pitch_um,
        offsets_um=None,
        field=(2.0, 2.0),
        wavelengths=None,
        normalization="sum",
        sampling="centers",
    ):
        """A PSFGrid of `psfs` (n_wavelengths, ny, nx, s, s) over ±`field` (x, y) degrees; chief rays =
        the ideal image points + `offsets_um` (n_wavelengths, ny, nx, 2) µm (x right, y up);
        wavelengths (nm) 531, 581, ... unless given."""
        from solas_mi.psf.grid import PSFGrid, field_nodes

        psfs = np.asarray(psfs, dtype=np.float32)
        nw, ny, nx = psfs.shape[:3]
        fx = field_nodes(nx, field[0], sampling)
        fy = field_nodes(ny, field[1], sampling)[::-1]
        fields = np.stack(np.meshgrid(fx, fy), axis=-1)
        chief = np.repeat(cls.focal_mm * np.tan(np.radians(fields))[None], nw, axis=0)
        if offsets_um is not None:
            chief = chief + np.asarray(offsets_um, dtype=np.float64) * 1e-3
        meta = {
            "normalization": normalization,
            "field_range_deg": list(field),
            "field_sampling": sampling,
            "pinhole_focal_mm": cls.focal_mm,
            "reference_wavelength_nm": 531.0,
            "lens": "synthetic",
            "lens_hash": "0" * 16,
        }
        wl = tuple(wavelengths) if wavelengths else tuple(531.0 + 50.0 * k for k in range(nw))
        return PSFGrid(psfs, fields, chief, wl, float(pitch_um), meta)

    def __call__(
        self, shape=(3, 4, 4), wavelengths=None, pitch_um=2.0, size=31, kind="gaussian", sigma_um=8.0, **options
    ):
        """A grid of `shape` (n_wavelengths, ny, nx) with the same PSF at every node: a Gaussian of σ
        `sigma_um` or a delta (`kind`), `size`² samples of `pitch_um`; `options` as `from_psfs`."""
        if kind not in self.KINDS:
            raise ValueError(f"kind {kind!r} must be one of {', '.join(self.KINDS)}")
        psf = self.gaussian(size, sigma_um, pitch_um) if kind == "gaussian" else self.delta(size)
        return self.from_psfs(np.broadcast_to(psf, (*shape, size, size)), pitch_um, wavelengths=wavelengths, **options)


@pytest.fixture(scope="session")
def synthetic_grid() -> SyntheticGrids:
    return SyntheticGrids()
