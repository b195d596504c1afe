"""`solas-mi crossval` and `solas-mi report error-vs-time`."""
from __future__ import annotations

from typing import Any

from . import crossval, error_vs_time


def register(sub: Any) -> None:
    crossval.register(sub)
    error_vs_time.register(sub)
