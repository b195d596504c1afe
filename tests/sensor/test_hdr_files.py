"""Odd HDR sensor files through `solas-mi camera`: a stage's table of the wrong shape, a key of a stage with a
value of the wrong type or out of range, readouts that cannot form a chain, knees that cannot compand: each
one line naming the file, the stage and what is allowed, and nothing written."""

import re

import numpy as np
import pytest
from test_odd_files import WRONG_TYPES, camera

from solas_mi.imageio import write_exr
from solas_mi.sensor.files import PRESETS

HDR = (PRESETS / "imx490-hdr.toml").read_text(encoding="utf-8")
READOUT_KEYS = (
    "name",
    "photodiode",
    "sensitivity",
    "exposure_ratio",
    "full_well_e",
    "read_noise_e",
    "dark_current_e_s",
    "gain_dn_per_e",
    "bit_depth",
    "black_level_dn",
    "prnu",
    "dsnu_e",
)


@pytest.fixture
def folder(tmp_path):
    write_exr(tmp_path / "in.exr", {c: np.full((12, 16), 0.02, np.float32) for c in "RGB"})
    return tmp_path


def run(folder, capsys, text):
    (folder / "hdr.toml").write_text(text, encoding="utf-8")
    return camera(folder, capsys, sensor=str(folder / "hdr.toml"))


def first_readout_with(key, value):
    """The preset with `key = value` in its first readout (its line there replaced)."""
    head, sep, rest = HDR.partition("[[sensor.readout]]\n")
    first, sep2, others = rest.partition("[[sensor.readout]]\n")
    lines = [line for line in first.split("\n") if not line.startswith(f"{key} =")]
    return head + sep + f"{key} = {value}\n" + "\n".join(lines) + sep2 + others


NAMES = ("name", "photodiode")  # strings: any printable one is a name


@pytest.mark.parametrize(
    "key, value", [(k, v) for k in READOUT_KEYS for v in WRONG_TYPES if not (k in NAMES and v.startswith('"'))]
)
def test_a_readout_key_of_the_wrong_type_is_one_line(folder, capsys, key, value):
    code, err = run(folder, capsys, first_readout_with(key, value))
    assert code == 2 and "hdr.toml" in err and "readout" in err and key in err, err


@pytest.mark.parametrize("key", NAMES)
def test_a_name_is_printable_and_not_empty(folder, capsys, key):
    code, err = run(folder, capsys, first_readout_with(key, '"a\\u0007b"'))
    assert code == 2 and f"{key} = 'a\\x07b' must be a non-empty printable name" in err, err
    code, err = run(folder, capsys, first_readout_with(key, '" "'))
    assert code == 2 and f"{key} = ' ' must be a non-empty printable name" in err, err
    assert run(folder, capsys, first_readout_with(key, '"1.0"'))[0] == 0


@pytest.mark.parametrize(
    "text, message",
    [
        ("[sensor]\n[sensor.merge]\nbits = 20\n", r"a sensor of 1 readout\(s\) takes no merge"),
        ("[sensor]\n[sensor.readout]\nname = 'a'\n", r"sensor readout must be \[\[sensor.readout\]\] tables"),
        (
            "[sensor]\nmerge = 3\n[[sensor.readout]]\n[[sensor.readout]]\nname = 'b'\ngain_dn_per_e = 0.1\n",
            r"sensor merge must be a table of Merge's fields",
        ),
        (
            "[sensor]\nfull_well_e = 3\n[[sensor.readout]]\n",
            r"unknown sensor parameter\(s\) full_well_e; allowed: .*readout",
        ),
        ("[sensor]\n[[sensor.readout]]\nwell = 3\n", r"unknown sensor readout parameter\(s\) well; allowed: name, "),
        (
            "[sensor]\n[[sensor.readout]]\n[[sensor.readout]]\ngain_dn_per_e = 0.1\n[sensor.merge]\n",
            r"sensor readout names \['linear', 'linear'\] must differ",
        ),
        (
            "[sensor]\n[[sensor.readout]]\nexposure_ratio = 2.0\n",
            r"sensor readout 'linear': exposure_ratio = 2.0 must be a number in \(0, 1\]",
        ),
        (HDR.replace("bits = 24 ", "bits = 25 "), r"sensor merge bits = 25 must be an integer from 16 to 24"),
        (
            HDR.replace("threshold = 0.9 ", "threshold = 0.0 "),
            r"sensor merge threshold = 0.0 must be a number in \(0, 1\]",
        ),
        (
            HDR + "[sensor.compander]\nknees = [[0, 0], [10, 20]]\n",
            r"compander knees = \[\[0, 0\], \[10, 20\]\] must start at",
        ),
        (
            HDR + "[sensor.compander]\nknees = [[0, 0], [16777215, 5000]]\n",
            r"compander's last knee's output 5000 plus black_level_dn 0 must be at most the 12-bit white level 4095",
        ),
        (HDR + "[sensor.compander]\nknees = 'log'\n", r"sensor compander knees = 'log' must be at least two points"),
    ],
)
def test_a_chain_that_cannot_be_is_one_line(folder, capsys, text, message):
    code, err = run(folder, capsys, text)
    assert code == 2 and re.search(message, err), err
    assert "hdr.toml" in err
