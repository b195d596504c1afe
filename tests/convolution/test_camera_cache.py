"""The camera block every output records is fitted once per lens, sensor and model and kept in the cache of
fitted cameras (`optics.calibration.describe_camera`, `caches.RecordCache`): a second degrade of the same frame
reads it back (no fit) and records the same block; a changed lens file, a corrupt or tampered record is fitted
again; a cache folder that cannot be written is no error."""

import dataclasses

import numpy as np
import pytest
from strict_json import strict_loads

from solas_mi import Lens
from solas_mi.cli import main
from solas_mi.imageio import read_exr, write_png
from solas_mi.optics.calibration import Sensor, describe_camera
from solas_mi.psf.grid import psf_grid
from solas_mi.psf.spec import GridSpec

SENSOR = Sensor(64, 48, 50.0)
MODEL = "opencv-pinhole"


@pytest.fixture
def fits(monkeypatch, fresh_cache):
    """The models fitted in this test (its own empty cache)."""
    from solas_mi.optics.calibration import fit as fitting

    made, real = [], fitting.fit
    monkeypatch.setattr(fitting, "fit", lambda cmap, name: made.append(name) or real(cmap, name))
    return made


def records(folder) -> list:
    return sorted((folder / "cameras").glob("*.json"))


def test_a_second_degrade_reads_its_camera_back(tmp_path, fits, fresh_cache):
    lens = Lens.load(Lens.load("solas-doublet").save(tmp_path / "doublet.toml"))  # a grid naming its lens file
    grid = psf_grid(
        lens, GridSpec(grid=(3, 3), size=15, method="geometric", rays=16, wavelengths_nm=(lens.primary_wavelength,))
    )
    grid.write(str(tmp_path / "grid.exr"))
    write_png(tmp_path / "f.png", np.full((48, 64, 3), 0.5))
    blocks = []
    for name in ("a.exr", "b.exr"):
        assert (
            main(
                [
                    "degrade",
                    str(tmp_path / "f.png"),
                    "--psf-grid",
                    str(tmp_path / "grid.exr"),
                    "--calibration-model",
                    MODEL,
                    "-o",
                    str(tmp_path / name),
                ]
            )
            == 0
        )
        blocks.append(read_exr(tmp_path / name)[1]["camera"])
    assert fits == [MODEL] and len(records(fresh_cache)) == 1
    assert blocks[0] == blocks[1] and blocks[0]["calibration"]["model"] == MODEL


def test_a_changed_lens_file_is_fitted_again(tmp_path, fits, fresh_cache):
    path = Lens.load("solas-doublet").save(tmp_path / "lens.toml")
    first = describe_camera(Lens.load(path), SENSOR, MODEL)
    lens = Lens.load(path)
    thicker = dataclasses.replace(lens.surfaces[0], thickness=lens.surfaces[0].thickness * 1.05)
    dataclasses.replace(lens, surfaces=(thicker, *lens.surfaces[1:])).save(path)  # same name, other content
    second = describe_camera(Lens.load(path), SENSOR, MODEL)
    assert fits == [MODEL, MODEL] and len(records(fresh_cache)) == 2
    assert first["lens"] == second["lens"] and first["lens_hash"] != second["lens_hash"]
    assert first["calibration"]["parameters"] != second["calibration"]["parameters"]


@pytest.mark.parametrize(
    "spoil",
    [
        lambda text: text[: len(text) // 2],  # truncated
        lambda text: text.replace('"rms_residual_px": ', '"rms_residual_px": 1'),  # changed, still JSON
        lambda text: "[]",  # not a record
    ],
)
def test_a_spoiled_record_is_fitted_again(doublet, fits, fresh_cache, capsys, spoil):
    first = describe_camera(doublet, SENSOR, MODEL)
    (record,) = records(fresh_cache)
    record.write_text(spoil(record.read_text()))
    assert describe_camera(doublet, SENSOR, MODEL) == first and fits == [MODEL, MODEL]
    assert f"cache entry {record} is not reused" in capsys.readouterr().err
    assert strict_loads(record.read_text())["value"] == first  # written whole again
    assert describe_camera(doublet, SENSOR, MODEL) == first and fits == [MODEL, MODEL]


def test_a_cache_that_cannot_be_written_is_no_error(tmp_path, doublet, fits, monkeypatch, capsys):
    from solas_mi.caches import ENV, RecordCache

    (tmp_path / "file").write_text("")
    monkeypatch.setenv(ENV, str(tmp_path / "file" / "cache"))  # under a file: no folder can be made, even by root
    monkeypatch.setattr(RecordCache, "unwritable", set())
    blocks = [describe_camera(doublet, SENSOR, MODEL) for _ in range(2)]
    assert blocks[0] == blocks[1] and fits == [MODEL, MODEL]
    assert capsys.readouterr().err.count("camera fit is not kept") == 1
