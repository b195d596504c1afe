"""Where the shipped scenes/ and plugins/ folders are, and which version of solas-mi is installed.

Resources are found through the package's own import path: `solas_mi.scenes` and `solas_mi.plugins`
are folders inside the installed package (a wheel), or mapped onto the checkout's top-level
scenes/ and plugins/ (an editable install, a source checkout). A top-level `scenes` or `plugins`
package that something else installed beside solas_mi is never looked at."""

from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent
DISTRIBUTION = "solas-mi"


def _is_checkout(folder: Path) -> bool:
    """Whether `folder` is the root of a solas-mi source checkout (its pyproject names solas-mi)."""
    try:
        return f'name = "{DISTRIBUTION}"' in (folder / "pyproject.toml").read_text(encoding="utf-8")
    except OSError:
        return False


def resource_dir(name: str) -> Path:
    """Path of the shipped folder `name` ("scenes" or "plugins"): solas_mi/<name> inside an installed
    wheel, else the top-level folder of the source checkout that holds this package."""
    inside = _PACKAGE / name
    if inside.is_dir():
        return inside
    if _is_checkout(_PACKAGE.parent):
        return _PACKAGE.parent / name
    raise FileNotFoundError(
        f"solas-mi's {name}/ folder is neither in {_PACKAGE} nor beside it in a source checkout: reinstall solas-mi"
    )


def installed_version() -> str:
    """The version in the installed distribution's metadata (pyproject's `version`), "0+unknown" for a
    source tree that was never installed."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(DISTRIBUTION)
    except PackageNotFoundError:
        return "0+unknown"
