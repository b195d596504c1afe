"""The `solas-mi lens <analysis>` commands and `lens report`: made from the registry (each command's
options are its entry's), each writing a PNG with strict JSON and CSV beside it, bad values refused by
name with nothing written, the report's index showing every analysis."""

import argparse
import csv

import pytest
from strict_json import strict_loads

from solas_mi.analysis.options import OPTIONS
from solas_mi.analysis.registry import ANALYSES
from solas_mi.cli import build_parser, iter_commands, main
from solas_mi.optics.commands import add_environment_options

COMMANDS = dict(iter_commands(build_parser()))
IDEAL = """name = "ideal"
wavelengths_nm = [550.0]
field_deg = 4.0
[[surface]]
radius = 0.0
thickness = 100.5
diameter = 12.5
stop = true
focal_length = 100.0
"""


def _lens_flags() -> set[str]:
    """The options of where the lens is (--temperature-c, ...), which every command that takes a lens has."""
    parser = argparse.ArgumentParser()
    add_environment_options(parser)
    return {a.option_strings[0] for a in parser._actions if a.option_strings}


def flags(parser) -> set[str]:
    return {a.option_strings[0] for a in parser._actions if a.option_strings} - {"-h", "-o"} - _lens_flags()


@pytest.mark.parametrize("name", list(ANALYSES))
def test_each_analysis_is_a_lens_command_with_its_registered_options(name):
    parser = COMMANDS[("lens", name)]
    assert flags(parser) == {OPTIONS[k].flag for k in ANALYSES[name].extra["keywords"]}
    assert ANALYSES[name].summary[1:] in " ".join(parser.format_help().split())  # (its first letter capitalised)


def test_the_report_takes_every_option():
    assert flags(COMMANDS[("lens", "report")]) == {o.flag for o in OPTIONS.values()}


def test_a_command_writes_the_figure_and_its_numbers(tmp_path, capsys):
    out = tmp_path / "dist.png"
    assert main(["lens", "distortion", "cooke-triplet", "--field-samples", "5", "-o", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    record = strict_loads(out.with_suffix(".json").read_text())
    assert record["analysis"] == "distortion" and record["lens"] == "cooke-triplet"
    rows = list(csv.reader(out.with_suffix(".csv").open()))
    assert rows[0] == record["columns"] and len(rows) == 6 and len(record["rows"]) == 5
    assert float(rows[3][0]) == record["rows"][2][0] == pytest.approx(10.0)


def test_undefined_values_are_empty_cells_and_null(tmp_path):
    """A ray blocked by an aperture has no aberration: null in the JSON, an empty CSV cell (never NaN)."""
    lens = tmp_path / "vignetted.toml"
    lens.write_text(
        IDEAL.replace(
            "diameter = 12.5", "diameter = 12.5\n[[surface]]\nradius = 0.0\nthickness = 0.0\ndiameter = 11.0"
        ).replace("thickness = 100.5", "thickness = 50.0")
    )
    out = tmp_path / "fan.png"
    assert main(["lens", "ray-fan", str(lens), "--fields", "0", "--fan-samples", "9", "-o", str(out)]) == 0
    record = strict_loads(out.with_suffix(".json").read_text())
    assert None in record["rows"][0] and ",," in out.with_suffix(".csv").read_text()


def status(argv) -> int:
    """The exit status of `solas-mi argv` (a usage error exits through argparse)."""
    try:
        return main(argv)
    except SystemExit as exc:
        return exc.code


@pytest.mark.parametrize(
    "argv, words",
    [
        (["lens", "mtf", "cooke-triplet", "--fields", "0,25"], "field 25 deg is beyond"),
        (["lens", "mtf-field", "cooke-triplet", "--frequencies", "900"], "at most the diffraction cut-off"),
        (["lens", "through-focus", "cooke-triplet", "--focus-range-um", "-10"], "focus range -10.0 um"),
        (["lens", "mtf", "cooke-triplet", "-o", "{tmp}/mtf.jpg"], "must end in .png"),
        (["lens", "wavefront", "cooke-triplet", "--zernike", "standard"], "invalid choice"),
    ],
)
def test_bad_values_are_refused_by_name_and_nothing_is_written(tmp_path, capsys, argv, words):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    if "-o" not in argv:
        argv += ["-o", str(tmp_path / "out.png")]
    assert status(argv) == 2
    assert words in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_the_report_shows_every_analysis(tmp_path):
    lens = tmp_path / "ideal.toml"
    lens.write_text(IDEAL)
    out = tmp_path / "report"
    assert (
        main(
            [
                "lens",
                "report",
                str(lens),
                "-o",
                str(out),
                "--pupil-samples",
                "32",
                "--rays",
                "16",
                "--field-samples",
                "3",
                "--focus-steps",
                "3",
                "--fan-samples",
                "5",
                "--rings",
                "2",
                "--fields",
                "0,4",
            ]
        )
        == 0
    )
    index = (out / "index.html").read_text()
    for name in ANALYSES:
        assert (out / f"{name}.png").is_file() and f"src='{name}.png'" in index
        strict_loads((out / f"{name}.json").read_text())
    assert "not computed" not in index


def test_the_guide_lists_every_analysis_as_the_registry_has_it():
    """docs/guide/analyses.md's table: one row per registered analysis, its command and summary."""
    import re
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs" / "guide" / "analyses.md").read_text()
    rows = dict(re.findall(r"^\| `solas-mi lens ([\w-]+)` \| (.+?) \|$", page, re.M))
    assert rows == {name: a.summary for name, a in ANALYSES.items()}
