"""The `solas-mi` command line. Each stage owns its sub-commands (`<stage>/commands.py`, a
`register(subparsers)` each); this module only composes them and turns user errors into one line
on stderr and exit status 2."""
from __future__ import annotations

import argparse
import sys

from .errors import SolasError


def build_parser() -> argparse.ArgumentParser:
    from .convolution import commands as convolution
    from .metrics import commands as metrics
    from .optics import commands as optics
    from .psf import commands as psf
    from .render import commands as render
    from .validation import commands as validation

    from . import __version__

    parser = argparse.ArgumentParser(prog="solas-mi", description=__doc__.split("\n")[0])
    parser.add_argument("--version", action="version", version=f"solas-mi {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    # in the order of the data: lens → PSFs → convolution; lens → scene → render; images → metrics; checks
    for area in (optics, psf, convolution, render, metrics, validation):
        area.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.run(args) or 0)
    except SolasError as exc:
        print(f"solas-mi {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
