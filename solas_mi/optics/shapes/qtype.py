"""Forbes' Qbfs asphere: a conic (and even terms) plus the departure φ u²(1 − u²) Σ a_m Q_m^bfs(u²),
`qbfs` = [a0, a1, …] (mm), u = r / `norm_radius` (`forbes`); its vertex curvature is bent by the terms."""

from __future__ import annotations

from dataclasses import dataclass

from .. import forbes
from .asphere import EvenAsphere


@dataclass(frozen=True)
class Qbfs(EvenAsphere):
    """An even asphere with Forbes' Qbfs departure `qbfs` normalised at `norm_radius` (mm)."""

    qbfs: tuple[float, ...] = ()
    norm_radius: float = 1.0
    kind = "qbfs"

    def terms(self) -> dict:
        return {**super().terms(), "qbfs": self.qbfs, "norm_radius": self.norm_radius}

    @property
    def section_curvatures(self) -> tuple[float, float]:
        """c + 2 Σ a_m Q_m^bfs(0)/ρ² in both sections."""
        c = self.curvature + 2.0 * forbes.qbfs_sum(0.0, self.qbfs)[0] / self.norm_radius**2
        return c, c

    def table(self) -> dict:
        return {**super().table(), "qbfs": list(self.qbfs), "norm_radius": self.norm_radius}
