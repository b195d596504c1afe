"""Error against run time (`solas_mi.validation.error_vs_time`), on a tiny image."""

import numpy as np
import pytest
from strict_json import strict_loads

from solas_mi.errors import SolasError
from solas_mi.validation.error_vs_time import error_vs_time


def test_error_vs_time_writes_every_case(doublet, tmp_path):
    image = 0.2 + np.random.default_rng(0).random((24, 32, 3))
    rows = error_vs_time(
        doublet,
        image,
        tmp_path,
        ref_spp=8,
        render_spp=(3,),
        interp_grids=((4, 3),),
        patch_grids=((4, 3),),
        repeats=1,
        log=lambda s: None,
    )
    assert [r.name for r in rows] == ["patch 4x3", "interp 4x3", "render 3 spp"]
    assert rows[-1].spp == 3 and rows[-1].psf_seconds == 0.0
    assert all(np.isfinite(r.errors.rel_rmse) and r.errors.rel_rmse > 0 for r in rows)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["error_vs_time.png", "report.json", "table.csv", "table.md"]
    assert "| interp 4x3 |" in (tmp_path / "table.md").read_text()
    report = strict_loads((tmp_path / "report.json").read_text())
    assert [r["name"] for r in report["rows"]] == [r.name for r in rows]


def test_bad_settings_are_a_solas_error(doublet):
    image = np.ones((24, 32, 3))
    with pytest.raises(SolasError, match="PSF kind"):
        error_vs_time(doublet, image, None, kind="wave")
    with pytest.raises(SolasError, match="repeats"):
        error_vs_time(doublet, image, None, repeats=0)
