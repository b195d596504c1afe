"""`make lint`'s type check: mypy on the public API, the packages with an `__all__` and the modules that define
its names, as the API reference page finds them (docs/tools/hooks.py `public_api`), so that the list is the
packages' own. Settings: pyproject.toml [tool.mypy]."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "tools"))
import hooks  # noqa: E402


def public_modules() -> list[str]:
    """The packages that export names and the modules that define them."""
    api = hooks.public_api()
    return sorted(
        {package for package, names in api.items() if names} | {module for names in api.values() for _, module in names}
    )


if __name__ == "__main__":
    modules = [arg for module in public_modules() for arg in ("-m", module)]
    sys.exit(subprocess.call([sys.executable, "-m", "mypy", *modules], cwd=ROOT))
