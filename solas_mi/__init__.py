"""solas-mi: physically based lens simulation for automotive camera images."""
from __future__ import annotations

from .errors import SolasError

__all__ = ["Lens", "SolasError"]
__version__ = "0.1.0"


def __getattr__(name: str):
    # Lens pulls in Dr.Jit; metrics users need not pay for it.
    if name == "Lens":
        from .lens import Lens

        return Lens
    raise AttributeError(name)
