"""The results tables (`solas_mi.validation.tables`)."""

import numpy as np

from solas_mi.validation.scores import compare
from solas_mi.validation.tables import Row, crossval_markdown, csv_text, error_vs_time_markdown


def rows() -> list[Row]:
    ref = 0.2 + np.random.default_rng(2).random((30, 40, 3))
    return [
        Row("interp 4x3", "interp", "geometric", "4x3", 0.5, 0.125, compare(ref * 1.01, ref)),
        Row("render 3 spp", "render", "—", "—", 0.0, 0.25, compare(ref * 1.02, ref), spp=3),
    ]


def test_markdown_tables_give_every_row_in_per_cent():
    for text, columns in ((crossval_markdown(rows(), "a note"), 13), (error_vs_time_markdown(rows(), "a note"), 11)):
        lines = text.splitlines()
        assert lines[1] == "|" + "---|" * columns and len(lines) == 6 and lines[-1] == "a note"
        assert all(line.count("|") == columns + 1 for line in lines[:4])
        assert "| interp 4x3 |" in lines[2] and "1.000 %" in lines[2] and "2.000 %" in lines[3]
    assert "| render 3 spp | — | 0.250 |" in error_vs_time_markdown(rows())


def test_csv_holds_every_number():
    head, interp, render = csv_text(rows()).splitlines()
    keys = head.split(",")
    assert keys[:4] == ["name", "method", "psf", "grid"] and "rel_rmse_edge_denoised" in keys
    assert dict(zip(keys, render.split(",")))["spp"] == "3" and dict(zip(keys, interp.split(",")))["spp"] == ""
    assert dict(zip(keys, render.split(",")))["total_seconds"] == "0.25"
