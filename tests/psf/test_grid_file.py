"""PSF grid files checked on read: every metadata field a user of the grid reads, with one clear
error naming the file and the field for a damaged one (no traceback, no silently different grid)."""

import math

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.imageio import META_KEY, read_exr
from solas_mi.psf.grid import PSFGrid, psf_grid


@pytest.fixture(scope="module")
def grid_file(tmp_path_factory, doublet):
    path = tmp_path_factory.mktemp("grid") / "grid.exr"
    psf_grid(doublet, grid=(2, 3), wavelengths_nm=[486.0, 656.0], size=16, pitch_um=2.0, pupil_samples=16).write(
        str(path)
    )
    return path


def damaged(grid_file, tmp_path, change) -> str:
    """A copy of the grid file whose channels and metadata `change(channels, meta)` altered, written as
    another writer may (Python's json: a NaN or an infinity as a bare token; `write_exr` refuses a NaN)."""
    import json

    import OpenEXR

    channels, meta = read_exr(grid_file)
    change(channels, meta)
    path = tmp_path / "damaged.exr"
    header = {"compression": OpenEXR.NO_COMPRESSION, "type": OpenEXR.scanlineimage, META_KEY: json.dumps(meta)}
    with OpenEXR.File(header, {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in channels.items()}) as f:
        f.write(str(path))
    return str(path)


def drop(key):
    return lambda channels, meta: meta.pop(key)


def put(key, value):
    return lambda channels, meta: meta.__setitem__(key, value)


@pytest.mark.parametrize(
    "change, field",
    [
        (drop("wavelengths_nm"), "wavelengths_nm"),
        (put("wavelengths_nm", "486,656"), "wavelengths_nm"),
        (put("wavelengths_nm", []), "wavelengths_nm"),
        (put("wavelengths_nm", [486.0, 486.0]), "wavelengths_nm"),
        (put("pitch_um", "2"), "pitch_um"),
        (put("pitch_um", math.nan), "pitch_um"),
        (put("pitch_um", -2.0), "pitch_um"),  # read as a different grid before
        (put("pitch_um", 0), "pitch_um"),
        (drop("pitch_um"), "pitch_um"),
        (put("grid", [2]), "grid"),
        (put("grid", "3x2"), "grid"),
        (put("grid", [3, 2]), "transmission"),  # a shape that disagrees with the other fields
        (put("size", 16.5), "size"),
        (put("size", 0), "size"),
        (lambda c, m: c.pop("psf_656nm"), "psf_656nm"),
        (lambda c, m: c.update({k: v[:-1] for k, v in c.items()}), "psf_486nm"),  # one row short
        (put("fields_deg", [[0.0, 1.0]]), "fields_deg"),
        (put("fields_deg", "none"), "fields_deg"),
        (drop("chief_ray_mm"), "chief_ray_mm"),
        (lambda c, m: m.__setitem__("chief_ray_mm", m["chief_ray_mm"][:1]), "chief_ray_mm"),
        (put("field_range_deg", [-2.0, 2.0]), "field_range_deg"),
        (put("field_range_deg", [2.0]), "field_range_deg"),
        (put("pinhole_focal_mm", "100"), "pinhole_focal_mm"),
        (put("reference_wavelength_nm", math.inf), "reference_wavelength_nm"),
        (put("normalization", "max"), "normalization"),
        (put("layout", "polar"), "layout"),
        (put("layout", "sensor"), "sensor_mm"),  # a sensor layout without its sensor and nodes
        (put("transmission", [[1.0]]), "transmission"),
    ],
)
def test_a_damaged_grid_names_the_file_and_the_field(grid_file, tmp_path, change, field):
    path = damaged(grid_file, tmp_path, change)
    with pytest.raises(SolasError, match=f"PSF grid {path}: .*{field}"):
        PSFGrid.read(path)


def test_an_intact_grid_reads_back(grid_file):
    g = PSFGrid.read(str(grid_file))
    assert g.data.shape == (2, 2, 3, 16, 16) and g.pitch_um == 2.0 and np.isfinite(g.chief_ray_mm).all()
