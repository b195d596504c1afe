"""`solas-mi lens <analysis>`: one command per entry of `registry.ANALYSES` (its options from
`options.OPTIONS`, its help from the entry), each writing a PNG and its numbers (.json, .csv) beside
it; `solas-mi lens report`: all of them into one folder with an index page (`report`). Light: the
analyses load when a command runs."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..optics.commands import add_lens_argument, load_lens
from .options import OPTIONS, command_options
from .registry import ANALYSES


def _lens_group(sub: Any):
    """The sub-commands of `solas-mi lens` (made by `optics.commands.register`)."""
    lens = sub.choices["lens"]
    return next(a for a in lens._actions if isinstance(a, argparse._SubParsersAction))


def _warn(result) -> None:
    for text in result.warnings:
        print(f"solas-mi: warning: {result.lens} {result.name}: {text}", file=sys.stderr)


def run_analysis(args) -> int:
    analysis = ANALYSES[args.lens_command]
    options = command_options(args, analysis.extra["keywords"])
    lens = load_lens(args)
    from .base import output_paths

    output_paths(args.output)  # checked before the work
    result = analysis.function(lens, **options)
    _warn(result)
    png, data, table = result.write(args.output)
    print(f"wrote {png}, {data}, {table}")
    return 0


def run_report(args) -> int:
    from .report import report

    lens = load_lens(args)
    index = report(
        lens,
        args.output,
        progress=lambda name: print(f"{name} ...", file=sys.stderr, flush=True),
        **command_options(args, tuple(OPTIONS)),
    )
    print(f"wrote {index}")
    return 0


def register(sub: Any) -> None:
    """Add `lens <analysis>` for each registered analysis, `lens report`, `thermal` and `tolerance`."""
    group = _lens_group(sub)
    for name, analysis in ANALYSES.items():
        p = group.add_parser(
            name,
            help=analysis.summary,
            description=f"{analysis.summary[0].upper()}{analysis.summary[1:]}. Reference: {analysis.reference}.",
        )
        add_lens_argument(p)
        for key in analysis.extra["keywords"]:
            OPTIONS[key].add_to(p)
        p.add_argument(
            "-o",
            "--output",
            default=f"{name}.png",
            help="the figure (PNG); its numbers are written beside it as .json and .csv",
        )
        p.set_defaults(run=run_analysis)
    report = group.add_parser(
        "report",
        help="every lens analysis into one folder, with an index page (HTML)",
        description="Every analysis of `solas-mi lens` (" + ", ".join(ANALYSES) + ") into "
        "one folder: each one's PNG, JSON and CSV, and index.html showing them all. Each "
        "option goes to the analyses that take it.",
    )
    add_lens_argument(report)
    for option in OPTIONS.values():
        option.add_to(report)
    report.add_argument("-o", "--output", required=True, help="the folder (made if need be)")
    report.set_defaults(run=run_report)
    from .thermal_report import register as register_thermal

    register_thermal(sub)
    from .tolerance_report import register as register_tolerance

    register_tolerance(sub)
