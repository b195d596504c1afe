"""`solas-mi thermal LENS --from -40 --to 105`: the sweep of `analysis.thermal` as a table on stdout and, in the
output folder, thermal.csv (one row per temperature), thermal.json (the rows, the lens and the settings)
and thermal.png (focus and MTF50 against temperature), written together."""

from __future__ import annotations

import sys
from pathlib import Path

from .. import jsonio
from ..outputs import output_folder, written_together
from . import inputs, thermal
from .options import OPTIONS

_FIELDS = {0.0: "axis", 0.7: "0.7 field", 1.0: "edge"}


def columns(row: dict) -> dict:
    """One sweep row as flat CSV columns: mtf50_<as_built|refocused>_<axis|0.7|edge>_<t|s>_cy_mm."""
    flat = {k: row[k] for k in ("temperature_c", "efl_mm", "bfd_mm", "best_focus_mm")}
    for focus, fields in row["mtf50_cy_mm"].items():
        for fraction, values in fields.items():
            for orientation, value in values.items():
                name = f"mtf50_{focus.replace(' ', '_')}_{_FIELDS[fraction].split()[0]}_{orientation[0]}_cy_mm"
                flat[name] = "" if value is None else value
    return flat


def table(rows: list[dict]) -> str:
    """The rows as text: T, EFL, BFD, best focus, then MTF50 tangential/sagittal per field, as built | refocused."""

    def pair(values) -> str:  # tangential/sagittal
        return "/".join("-" if v is None else f"{v:.0f}" for v in values.values())

    head = (
        f"{'T (°C)':>7s}{'EFL (mm)':>11s}{'BFD (mm)':>11s}{'focus (mm)':>11s}  MTF50 T/S (cy/mm): "
        + " ".join(f"{_FIELDS[f]:>9s}" for f in thermal.FIELD_FRACTIONS)
        + "  | refocused"
    )
    lines = [head]
    for r in rows:
        mtf = r["mtf50_cy_mm"]
        lines.append(
            f"{r['temperature_c']:7g}{r['efl_mm']:11.4f}{r['bfd_mm']:11.4f}{r['best_focus_mm']:11.4f}"
            + " " * 21
            + " ".join(f"{pair(mtf[thermal.FOCUS[0]][f]):>9s}" for f in thermal.FIELD_FRACTIONS)
            + "  | "
            + " ".join(f"{pair(mtf[thermal.FOCUS[1]][f]):>9s}" for f in thermal.FIELD_FRACTIONS)
        )
    return "\n".join(lines)


def _plot(rows: list[dict], lens_name: str, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = [r["temperature_c"] for r in rows]
    fig, (focus, mtf) = plt.subplots(1, 2, figsize=(11, 4.2))
    for key, label in (("efl_mm", "EFL"), ("bfd_mm", "back focus"), ("best_focus_mm", "best focus − image plane")):
        focus.plot(t, [(r[key] - rows[0][key]) * 1000.0 for r in rows], marker="o", ms=3, label=label)
    focus.set_xlabel("temperature (°C)")
    focus.set_ylabel(f"change from {t[0]:g} °C (µm)")
    focus.legend(fontsize=8)
    for i, fraction in enumerate(thermal.FIELD_FRACTIONS):
        for orientation, style in zip(rows[0]["mtf50_cy_mm"][thermal.FOCUS[0]][fraction], ("-", ":")):
            for focus_state, marker in zip(thermal.FOCUS, ("o", "x")):
                values = [r["mtf50_cy_mm"][focus_state][fraction][orientation] for r in rows]
                mtf.plot(
                    t,
                    [float("nan") if v is None else v for v in values],
                    style,
                    marker=marker,
                    ms=3,
                    color=f"C{i}",
                    label=f"{_FIELDS[fraction]} {orientation[0].upper()} {focus_state}",
                )
    mtf.set_xlabel("temperature (°C)")
    mtf.set_ylabel("MTF50 (cycles/mm)")
    mtf.legend(fontsize=6, ncol=2)
    fig.suptitle(f"{lens_name}: focus and MTF50 against temperature", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, format="png", dpi=100)
    plt.close(fig)


def write(rows: list[dict], lens, settings: dict, folder: str) -> list[Path]:
    """thermal.csv, thermal.json and thermal.png in `folder`, written together; their paths."""
    out = output_folder(folder)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "thermal.csv", out / "thermal.json", out / "thermal.png"]
    flat = [columns(r) for r in rows]
    csv = (
        ",".join(flat[0])
        + "\n"
        + "".join(",".join(repr(v) if isinstance(v, float) else str(v) for v in f.values()) + "\n" for f in flat)
    )
    rows_json = [
        {
            **r,
            "mtf50_cy_mm": {
                focus: {_FIELDS[f]: v for f, v in fields.items()} for focus, fields in r["mtf50_cy_mm"].items()
            },
        }
        for r in rows
    ]
    with written_together(*paths) as (tmp_csv, tmp_json, tmp_png):
        Path(tmp_csv).write_text(csv, encoding="utf-8")
        Path(tmp_json).write_text(
            jsonio.dumps(
                {"lens": lens.name, "hash": lens.hash, "source": lens.source, **settings, "rows": rows_json}, indent=2
            ),
            encoding="utf-8",
        )
        _plot(rows, lens.name, tmp_png)
    return paths


def run_thermal(args) -> int:
    """The `thermal` command: the sweep, its table on stdout, its files in -o DIR."""
    from ..optics.commands import load_lens
    from ..progress import Progress

    lens = load_lens(args)
    temps = thermal.temperatures(args.start_c, args.stop_c, args.step_c)
    pressure = lens.pressure_kpa if args.pressure_kpa is None else args.pressure_kpa
    samples = inputs.pupil_samples(OPTIONS["pupil_samples"].value(args))
    rows = thermal.sweep(
        lens, temps, pressure, args.mount, samples, Progress("thermal", len(temps), "temperatures", stream=sys.stderr)
    )
    mounts = args.mount or [s.mount or thermal.optics_thermal.DEFAULT_MOUNT for s in lens.surfaces]
    settings = {
        "pressure_kpa": pressure,
        "mount": mounts,
        "pupil_samples": samples,
        "wavelengths_nm": list(lens.wavelengths_nm),
        "field_deg": lens.field_deg,
    }
    for text in dict.fromkeys(w for r in rows for w in r["warnings"]):
        print(f"solas-mi thermal: warning: {text}", file=sys.stderr)
    print(table(rows))
    paths = write(rows, lens, settings, args.output)
    print(f"wrote {', '.join(str(p) for p in paths)}")
    return 0


def register(sub) -> None:
    """Add `thermal`."""
    from ..optics.commands import add_lens_argument

    p = sub.add_parser(
        "thermal",
        help="EFL, back focus, best focus and MTF50 (axis, 0.7 field, edge; as built and "
        "refocused) of a lens from one temperature to another",
    )
    add_lens_argument(p)
    p.add_argument("--from", dest="start_c", type=float, default=-40.0, help="first temperature (°C)")
    p.add_argument("--to", dest="stop_c", type=float, default=105.0, help="last temperature (°C)")
    p.add_argument("--step-c", type=float, default=15.0, help="temperature step (°C); the last is --to")
    OPTIONS["pupil_samples"].add_to(p)
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder: thermal.csv, .json, .png")
    p.set_defaults(run=run_thermal)


__all__: list[str] = []
