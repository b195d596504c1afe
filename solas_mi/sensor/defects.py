"""`Defects`, the stage of a sensor's chain that holds its defect pixels: dead pixels, which collect no light,
and hot pixels, whose dark current is higher by `hot_dark_current_e_s` (in every photodiode of the pixel).

Which pixels are defects is fixed per sensor (its seed), from the stage's own stream [seed, 4, id], and a hot
pixel's extra dark electrons are Poisson, from [seed, 5, id, frame, charge] (id the CRC-32 of "defects"), so
a sensor without defects, and every other pixel of one with them, gives the frames it gave without."""

from __future__ import annotations

import zlib
from dataclasses import asdict, dataclass

import numpy as np

from .limits import ELECTRONS_MAX, check_number

STREAM = zlib.crc32(b"defects")
FRACTION_MAX = 0.01  # 1 % of the pixels: far past any sensor shipped (data sheets: ppm)


@dataclass(frozen=True)
class Defects:
    """The fractions of dead and hot pixels, and a hot pixel's extra dark current (e⁻/s)."""

    dead_fraction: float = 0.0
    hot_fraction: float = 0.0
    hot_dark_current_e_s: float = 1000.0

    def __post_init__(self):
        for name in ("dead_fraction", "hot_fraction"):
            check_number(
                getattr(self, name), name, 0.0, FRACTION_MAX, "a fraction of the pixels", where="sensor defects"
            )
        check_number(
            self.hot_dark_current_e_s,
            "hot_dark_current_e_s",
            0.0,
            ELECTRONS_MAX,
            "a hot pixel's extra dark current in e⁻/s",
            where="sensor defects",
        )

    def describe(self) -> dict:
        return asdict(self)

    def pixel_map(self, shape: tuple[int, int], seed: int) -> tuple[np.ndarray, np.ndarray]:
        """Where the dead and the hot pixels of sensor `seed` are (two boolean maps, disjoint).

        Parameters
        ----------
        shape : (int, int)
            The frame's (height, width).
        seed : int
            The sensor's seed.

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            The dead and the hot pixels.
        """
        draw = np.random.default_rng([seed, 4, STREAM]).random(shape)
        dead = draw < self.dead_fraction
        return dead, ~dead & (draw < self.dead_fraction + self.hot_fraction)

    def hot_electrons(
        self, hot: np.ndarray, seconds: float, cap: float, seed: int, frame: int, charge: int
    ) -> np.ndarray:
        """A charge's extra dark electrons on the hot pixels over `seconds` (Poisson, at most `cap` as mean).

        Parameters
        ----------
        hot : numpy.ndarray
            The hot pixels (`pixel_map`).
        seconds : float
            The charge's exposure (s).
        cap : float
            The largest Poisson mean (past the well the count is clipped anyway).
        seed, frame : int
            The sensor's seed and the frame's number.
        charge : int
            The charge's index in the chain.

        Returns
        -------
        numpy.ndarray
            One count per hot pixel (in `hot`'s row-major order).
        """
        rng = np.random.default_rng([seed, 5, STREAM, frame, charge])
        return rng.poisson(min(self.hot_dark_current_e_s * seconds, cap), int(np.count_nonzero(hot)))
