"""The ideal thin lens: a plane that bends rays by its `focal_length` (mm) without a glass change
(`optics.ideal`: the deflection and its optical path)."""

from __future__ import annotations

from dataclasses import dataclass

from .plane import Plane


@dataclass(frozen=True)
class IdealLens(Plane):
    """A flat ideal thin lens of `focal_length` (mm)."""

    focal_length: float = 0.0
    kind = "ideal"

    def table(self) -> dict:
        return {"radius": 0.0, "focal_length": self.focal_length}
