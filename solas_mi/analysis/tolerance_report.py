"""`solas-mi tolerance LENS --spec TOL.toml --samples N --seed S -o DIR`: the Monte Carlo of `analysis.tolerance`
into a folder: lenses/sample_NNNNN.toml (each drawn lens as assembled: its image plane where the
compensator put it; a lens file every command reads, e.g. `batch degrade --lens-population`), samples.csv
(each sample's deltas, EFL, focus shift and MTF50 per field), sensitivity.csv (each tolerance alone),
tolerance.json (the settings, the nominal lens's figures, MTF50 percentiles per field, the yield) and
tolerance.png (MTF50 against field: nominal, median and the 10–90 % band, the limit), written together;
a summary on stdout."""

from __future__ import annotations

import sys
from pathlib import Path

from .. import jsonio
from ..outputs import output_folder, written_together
from . import tolerance
from .base import defined
from .options import OPTIONS

_ORIENTATIONS = ("tangential", "sagittal")


def _csv(rows: list[dict]) -> str:
    """Flat dicts as CSV text (floats in full)."""
    cell = lambda v: repr(v) if isinstance(v, float) else str(v)  # noqa: E731
    return ",".join(rows[0]) + "\n" + "".join(",".join(cell(v) for v in r.values()) + "\n" for r in rows)


def sample_columns(row: dict, spec) -> dict:
    """One sample as flat CSV columns: its deltas (by term), figures and MTF50 per field and orientation."""
    flat = {"sample": row["index"], "hash": row["hash"]}
    flat.update({f"{t.name} ({t.unit})": d for t, d in zip(spec.terms, row["deltas"])})
    flat.update({k: row[k] for k in ("efl_mm", "bfd_mm", "focus_shift_mm")})
    for field, values in zip(row["fields_deg"], row["mtf50_cy_mm"]):
        for orientation, value in zip(_ORIENTATIONS, values):
            flat[f"mtf50_{field:g}deg_{orientation[0]}_cy_mm"] = float(value)
    flat["worst_mtf50_cy_mm"] = tolerance.worst(row["mtf50_cy_mm"])
    return flat


def _listed(values) -> list | float | None:
    """An array of MTF50s as nested lists, None where the MTF never falls to 1/2 (NaN)."""
    return [_listed(v) for v in values] if getattr(values, "ndim", 0) else defined(float(values))


def _plot(nominal: dict, spread: dict, summary: dict, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fields = nominal["fields_deg"]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for j, (ax, orientation) in enumerate(zip(axes, _ORIENTATIONS)):
        ax.fill_between(fields, spread[10][:, j], spread[90][:, j], alpha=0.3, label="10-90 % of samples")
        ax.plot(fields, spread[50][:, j], marker=".", label="median")
        ax.plot(fields, nominal["mtf50_cy_mm"][:, j], "k--", label="nominal")
        if summary["mtf50_limit_cy_mm"] is not None:
            ax.axhline(summary["mtf50_limit_cy_mm"], color="C3", lw=1, label="limit")
        ax.set(title=orientation, xlabel="field (deg)", xlim=(min(0.0, fields[0]), fields[-1]))
        ax.grid(alpha=0.3)
    axes[0].set_ylabel(f"MTF50 (cycles/mm), back focus: {summary['settings']['compensator']}")
    axes[0].set_ylim(bottom=0)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"{summary['lens']}: MTF50 of {summary['samples']} samples (seed {summary['seed']})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, format="png", dpi=100)
    plt.close(fig)


def write(folder, spec, rows, sensitivity, nominal: dict, summary: dict) -> list[Path]:
    """Each sample's lens file, samples.csv, sensitivity.csv, tolerance.json and tolerance.png, all written
    together in `folder` (none changed if one fails); the lens files' folder and the others' paths."""
    from ..optics.lens_toml import dumps
    from ..optics.tolerance import LENS_FOLDER

    out = output_folder(folder)
    (out / LENS_FOLDER).mkdir(parents=True, exist_ok=True)
    lens_files = [out / LENS_FOLDER / f"sample_{row['index']:05d}.toml" for row in rows]
    paths = [out / name for name in ("samples.csv", "sensitivity.csv", "tolerance.json", "tolerance.png")]
    spread = tolerance.percentiles(rows)
    with written_together(*paths, *lens_files) as (samples_csv, sensitivity_csv, data, png, *lens_tmps):
        for row, tmp in zip(rows, lens_tmps):
            Path(tmp).write_text(dumps(row["lens"]), encoding="utf-8")
        Path(samples_csv).write_text(_csv([sample_columns(r, spec) for r in rows]), encoding="utf-8")
        Path(sensitivity_csv).write_text(_csv(sensitivity) if sensitivity else "", encoding="utf-8")
        Path(data).write_text(jsonio.dumps(summary, indent=2), encoding="utf-8")
        _plot(nominal, spread, summary, png)
    return [out / LENS_FOLDER, *paths]


MTF_NOTES = {
    "diffraction": "the polychromatic diffraction MTF at 0 ... half field (a lens symmetric about its axis)",
    "geometric": "the geometric MTF (no diffraction) at the primary wavelength of every lens, the nominal too, "
    "at signed fields along y (lenses as built: decentre, tilt or sensor tilt)",
}


def summarise(lens, spec, settings, rows, nominal, limit, seed) -> dict:
    """tolerance.json's content: the settings, nominal figures, percentiles per field and the yield."""
    spread = tolerance.percentiles(rows)
    fraction, error = tolerance.yield_fraction(rows, limit) if limit is not None else (None, None)
    return {
        "lens": lens.name,
        "hash": lens.hash,
        "source": lens.source,
        "seed": seed,
        "samples": len(rows),
        "test_wavelength_nm": spec.test_wavelength_nm,
        "terms": [
            {
                "name": t.name,
                "unit": t.unit,
                "value": t.value,
                "distribution": t.distribution,
                "truncate_sigma": t.truncate if t.distribution == "normal" else None,
            }
            for t in spec.terms
        ],
        "settings": {
            "compensator": settings.compensator,
            "field_samples": settings.field_samples,
            "pupil_samples": settings.pupil_samples,
            "mtf": settings.mtf,
            "mtf_note": MTF_NOTES[settings.mtf],
        },
        "nominal": {
            **{k: v for k, v in nominal.items() if k not in ("warnings", "mtf50_cy_mm", "assembled")},
            "mtf50_cy_mm": _listed(nominal["mtf50_cy_mm"]),
        },
        "percentiles_mtf50_cy_mm": {str(p): _listed(v) for p, v in spread.items()},
        "mtf50_limit_cy_mm": limit,
        "yield": fraction,
        "yield_standard_error": error,
    }


def _say(summary: dict) -> str:
    """The summary on stdout: MTF50 percentiles per field (T/S) and the yield."""
    lines = [f"{'field (deg)':>12s}  nominal T/S   " + "  ".join(f"{p:>3d}% T/S  " for p in tolerance.PERCENTILES)]
    spread, nominal = summary["percentiles_mtf50_cy_mm"], summary["nominal"]
    pair = lambda values: "/".join("-" if x is None else f"{x:.0f}" for x in values)  # noqa: E731
    for i, field in enumerate(nominal["fields_deg"]):
        lines.append(
            f"{field:12g}  {pair(nominal['mtf50_cy_mm'][i]):>11s}   "
            + "  ".join(f"{pair(spread[str(p)][i]):>9s}" for p in tolerance.PERCENTILES)
        )
    lines.append(f"MTF50: {summary['settings']['mtf_note']}")
    if summary["yield"] is not None:
        lines.append(
            f"yield (worst MTF50 >= {summary['mtf50_limit_cy_mm']:g} cy/mm): "
            f"{100 * summary['yield']:.1f} % ± {100 * summary['yield_standard_error']:.1f} %"
        )
    return "\n".join(lines)


def run_tolerance(args) -> int:
    """The `tolerance` command."""
    from ..optics.commands import load_lens
    from ..optics.tolerance import read_spec
    from ..optics.tolerance_placement import is_as_built
    from ..progress import Progress
    from . import inputs

    lens = load_lens(args)
    spec = read_spec(lens, args.spec)
    tolerance.check_run(args.samples, args.seed, args.workers)
    if args.mtf50_limit is not None:
        tolerance.check_limit(args.mtf50_limit)
    output_folder(args.output)
    settings = tolerance.Settings(
        spec.compensator,
        inputs.count(args.field_samples, "field samples", 2, 64),
        inputs.pupil_samples(OPTIONS["pupil_samples"].value(args)),
        tolerance.MTF_METHODS[is_as_built(spec)],
    )
    nominal = tolerance.evaluate(lens, settings)
    rows = tolerance.monte_carlo(
        lens,
        spec,
        args.samples,
        args.seed,
        settings,
        args.workers,
        Progress("tolerance", args.samples, "lenses", stream=sys.stderr),
    )
    sensitivity = (
        []
        if args.no_sensitivity
        else tolerance.sensitivity(
            lens, spec, settings, Progress("sensitivity", len(spec.terms), "tolerances", stream=sys.stderr)
        )
    )
    for text in dict.fromkeys(w for r in [nominal, *rows] for w in r["warnings"]):
        print(f"solas-mi tolerance: warning: {text}", file=sys.stderr)
    summary = summarise(lens, spec, settings, rows, nominal, args.mtf50_limit, args.seed)
    print(_say(summary))
    paths = write(args.output, spec, rows, sensitivity, nominal, summary)
    print(f"wrote {', '.join(str(p) for p in paths)}")
    return 0


def register(sub) -> None:
    """Add `tolerance`."""
    from ..optics.commands import add_lens_argument

    p = sub.add_parser(
        "tolerance",
        help="Monte Carlo of a lens's tolerances (a TOML file): the drawn lenses, their MTF50 per "
        "field (percentiles, a plot), each tolerance's sensitivity and the yield against an MTF50 limit",
    )
    add_lens_argument(p)
    p.add_argument(
        "--spec",
        required=True,
        metavar="TOL.toml",
        help="the tolerance file (kinds, units, distributions, the back-focus compensator)",
    )
    p.add_argument("--samples", type=int, default=100, help="lenses drawn (default: 100)")
    p.add_argument(
        "--seed",
        type=int,
        default=0,
        help="the Monte Carlo's seed: sample i is drawn from (seed, i) "
        "alone, the same lens on any number of workers (default: 0)",
    )
    p.add_argument(
        "--mtf50-limit",
        type=float,
        metavar="CY_MM",
        help="the yield: the fraction of samples whose "
        "MTF50 reaches this (cycles/mm) at every field, tangential and sagittal",
    )
    p.add_argument(
        "--field-samples",
        type=int,
        default=tolerance.Settings.field_samples,
        help=f"fields from 0 to the half field (default: {tolerance.Settings.field_samples})",
    )
    OPTIONS["pupil_samples"].add_to(p)
    p.add_argument("--workers", type=int, default=1, help="local processes measuring the samples (default: 1)")
    p.add_argument("--no-sensitivity", action="store_true", help="skip the table of each tolerance alone")
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="DIR",
        help="output folder: lenses/, samples.csv, sensitivity.csv, tolerance.json, tolerance.png",
    )
    p.set_defaults(run=run_tolerance)


__all__: list[str] = []
