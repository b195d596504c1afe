"""Package-level names imported on first use (PEP 562), so that importing a light module of a
package never loads the heavy ones (Dr.Jit, Mitsuba, matplotlib) its siblings need."""

from __future__ import annotations

import importlib


def lazy_exports(package: str, names: dict[str, str]):
    """A module `__getattr__` for `package` that imports each of `names` (name → relative module)
    when it is first asked for."""

    def __getattr__(name: str):
        if name not in names:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(names[name], package), name)

    return __getattr__
