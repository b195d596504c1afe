"""Strict JSON (`solas_mi.jsonio`): infinities written as "inf"/"-inf", no NaN written, old files with
`Infinity` tokens read as the new ones, our readers round-trip."""

import json
import math
from dataclasses import asdict

import numpy as np
import pytest
from strict_json import exr_meta, strict_loads

from solas_mi import jsonio
from solas_mi.errors import SolasError


def test_infinities_are_the_strings_inf_and_numbers_stay_as_pythons_json_writes_them():
    value = {
        "far": math.inf,
        "near": [-math.inf, 0.1, 1e-300],
        "f32": np.float32(0.5),
        "f64": np.float64(-np.inf),
        "n": np.int64(3),
        "flag": True,
        "none": None,
        "t": (1, 2.5),
    }
    text = jsonio.dumps(value, indent=1)
    assert strict_loads(text) == {
        "far": "inf",
        "near": ["-inf", 0.1, 1e-300],
        "f32": 0.5,
        "f64": "-inf",
        "n": 3,
        "flag": True,
        "none": None,
        "t": [1, 2.5],
    }
    finite = {"a": [0.1, 1 / 3, 2.0, 1e-300, -7.25e22], "b": {"c": 123456789.123456789}}
    assert jsonio.dumps(finite, indent=1) == json.dumps(finite, indent=1)  # finite floats: the same text
    assert float(strict_loads(text)["far"]) == math.inf and float(strict_loads(text)["near"][0]) == -math.inf


@pytest.mark.parametrize("nan", [math.nan, np.float32("nan"), np.nan])
def test_a_nan_is_an_error_naming_its_key(nan):
    with pytest.raises(SolasError, match=r"items\[1\]\.seconds is NaN"):
        jsonio.dumps({"items": [{"seconds": 1.0}, {"seconds": nan}]})


def test_old_infinity_tokens_read_as_the_new_strings():
    value = {"focus_distance": math.inf, "z": [-math.inf, 2.0]}
    old = json.dumps(value)  # what solas-mi wrote before: bare Infinity tokens
    assert "Infinity" in old
    assert jsonio.loads(old) == jsonio.loads(jsonio.dumps(value)) == {"focus_distance": "inf", "z": ["-inf", 2.0]}
    assert math.isnan(jsonio.loads('{"x": NaN}')["x"])  # an old NaN reads as it was


def test_exr_metadata_with_a_nan_is_refused_before_anything_is_written(tmp_path):
    from solas_mi.imageio import read_exr, write_exr

    path = tmp_path / "m.exr"
    with pytest.raises(SolasError, match=r"m\.exr: metadata: noise\.rms is NaN"):
        write_exr(path, {"Y": np.zeros((2, 2), np.float32)}, {"noise": {"rms": math.nan}})
    assert list(tmp_path.iterdir()) == []
    write_exr(path, {"Y": np.zeros((2, 2), np.float32)}, {"object_distance": math.inf})
    assert exr_meta(path) == {"object_distance": "inf"} == read_exr(path)[1]


def _job(tmp_path, **stamps):
    from solas_mi.batch.jobs import Job

    return Job(
        str(tmp_path / "in.png"),
        str(tmp_path / "a.exr"),
        str(tmp_path / "a.png"),
        kind="render",
        params={"focus_distance": math.inf, "object": [-math.inf, 1.5], "sensor": [2, 3]},
        **stamps,
    )


def test_a_manifest_written_with_infinity_tokens_still_resumes_and_is_rewritten_strict(tmp_path):
    """A batch.json of an earlier version (bare Infinity in an item's parameters) is read as the new
    form: its finished items are skipped; the manifest saved again is strict JSON and resumes too."""
    from solas_mi.batch.jobs import Manifest

    for name in ("in.png", "a.exr", "a.png"):
        (tmp_path / name).write_text(name)
    done = _job(tmp_path, status="done")
    done.stamp()
    path = tmp_path / "batch.json"
    path.write_text(json.dumps({"batch_id": "k", "items": [asdict(done)]}))
    assert "Infinity" in path.read_text()
    for _ in range(2):  # the old file, then the one saved by the resumed batch
        job = _job(tmp_path)
        manifest = Manifest(path, {"batch_id": "k"}, [job])
        assert manifest.resume("k") == 1 and job.status == "skipped"
        manifest.save()
        assert strict_loads(path.read_text())["items"][0]["params"]["focus_distance"] == "inf"


def test_json_nested_beyond_the_parser_is_a_value_error():
    """A manifest or record nested thousands deep (a damaged or hostile file): SolasError, a ValueError as
    `json`'s own errors are, which the readers of such files catch (before: RecursionError)."""
    with pytest.raises(SolasError, match="nested deeper than the parser goes"):
        jsonio.loads("[" * 100_000 + "]" * 100_000)
