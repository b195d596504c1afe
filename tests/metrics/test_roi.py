"""The ROI box: "x,y,w,h" text and the crop it selects."""

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.metrics.roi import crop, parse_roi


def test_crop_leaving_the_image_or_too_small_raises():
    img = np.zeros((50, 60))
    with pytest.raises(SolasError, match="leaves"):
        crop(img, (50, 0, 20, 20))
    with pytest.raises(SolasError, match="too small"):
        crop(img, (0, 0, 5, 20))


def test_parse_roi():
    with pytest.raises(SolasError, match="malformed"):
        parse_roi("1,2,3")
    with pytest.raises(SolasError, match="malformed"):
        parse_roi("a,b,c,d")
    assert parse_roi("1,2,30,40") == (1, 2, 30, 40)
