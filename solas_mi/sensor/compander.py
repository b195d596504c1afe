"""`Compander`, the stage that squeezes a merged linear HDR signal (20-24 bits) into the output's bits
(12-16) on chip, as automotive sensors do, and its inverse, the image processor's decompanding.

The curve is piecewise linear through knee points (x, y) as data sheets give them (x a merged code, y an
output code): from (0, 0), both rising, each segment's slope at most 1 and at most the one before it (a
compander compresses highlights), the last knee at the merged signal's white level. An output code is
y = round(f(x)) + black; decompanding gives f⁻¹(y − black), within half a code of segment k's
quantisation step Δx_k / Δy_k of the linear value (`Compander.step`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from .limits import check_adc

COMPANDED_BITS = (8, 16)  # the output's bits after companding


@dataclass(frozen=True)
class Compander:
    """Knee points (x, y): merged code → output code (module docstring); the output's bits and black level
    (added after companding)."""

    knees: tuple[tuple[int, int], ...] = ()
    bit_depth: int = 12
    black_level_dn: int = 0

    def __post_init__(self):
        check_adc(self.bit_depth, self.black_level_dn, where="sensor compander", bits=COMPANDED_BITS)
        pairs = self.knees if isinstance(self.knees, (list, tuple)) else None
        if (
            not pairs
            or len(pairs) < 2
            or not all(
                isinstance(p, (list, tuple))
                and len(p) == 2
                and all(isinstance(v, int) and not isinstance(v, bool) for v in p)
                for p in pairs
            )
        ):
            raise SolasError(
                f"sensor compander knees = {self.knees!r} must be at least two points [x, y] of integer "
                "codes (merged → output), from [0, 0]"
            )
        knees = tuple(tuple(p) for p in pairs)
        object.__setattr__(self, "knees", knees)
        xs, ys = np.array(knees, dtype=np.float64).T
        slopes = np.diff(ys) / np.where(np.diff(xs) > 0, np.diff(xs), np.nan)
        if (
            knees[0] != (0, 0)
            or not np.all(np.diff(xs) > 0)
            or not np.all(np.diff(ys) > 0)
            or not np.all(slopes <= 1.0)
            or not np.all(np.diff(slopes) <= 0.0)
        ):
            raise SolasError(
                f"sensor compander knees = {list(map(list, knees))} must start at [0, 0] with x and y "
                "rising and each segment's slope at most 1 and at most the one before (a compander "
                "compresses highlights)"
            )
        if ys[-1] + self.black_level_dn > self.white_level_dn:
            raise SolasError(
                f"sensor compander's last knee's output {int(ys[-1])} plus black_level_dn "
                f"{self.black_level_dn} must be at most the {self.bit_depth}-bit white level "
                f"{self.white_level_dn}"
            )

    def describe(self) -> dict:
        return {
            "knees": [list(p) for p in self.knees],
            "bit_depth": self.bit_depth,
            "black_level_dn": self.black_level_dn,
        }

    @property
    def white_level_dn(self) -> int:
        return 2**self.bit_depth - 1

    @property
    def top(self) -> int:
        """The merged code of the last knee: the merged signal's white level."""
        return self.knees[-1][0]

    def _points(self) -> tuple[np.ndarray, np.ndarray]:
        xs, ys = np.array(self.knees, dtype=np.float64).T
        return xs, ys

    def compand(self, merged: np.ndarray) -> np.ndarray:
        """Output codes (H, W, uint16) of merged codes."""
        xs, ys = self._points()
        out = np.rint(np.interp(np.asarray(merged, dtype=np.float64), xs, ys)) + self.black_level_dn
        return np.clip(out, 0, self.white_level_dn).astype(np.uint16)

    def decompand(self, codes: np.ndarray) -> np.ndarray:
        """The merged signal (float64, merged DN above black) of output codes: the inverse curve."""
        xs, ys = self._points()
        return np.interp(np.asarray(codes, dtype=np.float64) - self.black_level_dn, ys, xs)

    def step(self, merged: np.ndarray) -> np.ndarray:
        """The quantisation step Δx/Δy (merged codes per output code) of the segment of each merged code."""
        xs, ys = self._points()
        segment = np.clip(np.searchsorted(xs, np.asarray(merged, dtype=np.float64), side="right") - 1, 0, len(xs) - 2)
        return (np.diff(xs) / np.diff(ys))[segment]
