"""`solas-mi lens report`: every registered analysis of a lens into one folder (each one's PNG, JSON and
CSV) and an index page, index.html, that shows them with the lens's first-order data, each figure's
key numbers, conventions and warnings — what a designer sends a colleague. The options given are
checked first, then each goes to the analyses that take it."""

from __future__ import annotations

import html
import sys
from collections.abc import Callable
from pathlib import Path

from ..errors import SolasError
from ..imageio import write_text
from ..optics.paraxial import paraxial
from ..outputs import hold_folder, output_folder
from ..resources import installed_version
from . import inputs
from . import options as O
from .registry import ANALYSES

INDEX = "index.html"
STYLE = (
    "body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}img{max-width:100%;"
    "border:1px solid #ddd}table{border-collapse:collapse}td,th{padding:2px 10px;text-align:left;"
    "border-bottom:1px solid #eee}.warning{color:#a40}section{margin-bottom:2.5em}"
)


def check_options(lens, options: dict) -> None:
    """Each given option checked as the analyses that take it will, before any of them runs."""
    given = {k: v for k, v in options.items() if v is not None}
    unknown = sorted(set(given) - set(O.OPTIONS))
    if unknown:
        raise SolasError(f"unknown report options {', '.join(unknown)}; allowed: {', '.join(O.OPTIONS)}")
    wl, _ = inputs.wavelengths(lens, given.get("wavelengths_nm"), given.get("weights"))
    checks = {
        "fields_deg": lambda v: inputs.fields(lens, v),
        "wavelength_nm": lambda v: inputs.wavelength(lens, v),
        "frequencies_cy_mm": lambda v: inputs.frequencies(lens, v, wl),
        "frequency_cy_mm": lambda v: inputs.frequencies(lens, [v], wl),
        "max_frequency_cy_mm": lambda v: inputs.max_frequency(lens, v, wl),
        "focus_range_um": lambda v: inputs.focus_range(lens, v),
        "zernike": lambda v: inputs.choice(v, tuple(O.ZERNIKE_KINDS), "Zernike kind"),
        "energy_reference": lambda v: inputs.choice(v, O.ENERGY_REFERENCES, "energy reference"),
    }
    for key, value in given.items():
        checks.get(key, lambda v: None)(value)
    inputs.pixel(given.get("pixel_pitch_um"), given.get("fill_factor", 1.0))


def report(lens, folder, progress: Callable[[str], None] | None = None, **options) -> Path:
    """Run every analysis of `registry.ANALYSES` on `lens` with the `options` each takes (keywords of
    `options.OPTIONS`), write them into `folder` and its index page; the index's path. An analysis
    that fails on this lens (a SolasError) is named on the page and on stderr, the others go on."""
    check_options(lens, options)
    folder = output_folder(folder)
    sections = []
    with hold_folder(folder, f"solas-mi lens report {lens.name}"):
        for name in ANALYSES:
            analysis = ANALYSES[name]
            if progress:
                progress(analysis.name)
            own = {k: v for k, v in options.items() if k in analysis.extra["keywords"] and v is not None}
            try:
                result = analysis.function(lens, **own)
                result.write(folder / f"{analysis.name}.png")
            except SolasError as exc:
                print(f"solas-mi: lens report {lens.name}: {analysis.name} not computed: {exc}", file=sys.stderr)
                sections.append(_failed(analysis, str(exc)))
                continue
            sections.append(_section(analysis, result))
        index = folder / INDEX
        write_text(index, _page(lens, sections))
    return index


def _section(analysis, result) -> str:
    summary = result.table().summary
    parts = [
        f"<section id='{analysis.name}'><h2>{analysis.name}</h2><p>{html.escape(analysis.summary)}.</p>",
        f"<img src='{analysis.name}.png' alt='{analysis.name}'>",
        f"<p>Numbers: <a href='{analysis.name}.json'>JSON</a>, <a href='{analysis.name}.csv'>CSV</a>. "
        f"Reference: {html.escape(analysis.reference)}.</p>",
    ]
    if summary:
        parts.append(f"<details><summary>key numbers</summary><pre>{html.escape(_plain(summary))}</pre></details>")
    parts.append("<ul>" + "".join(f"<li>{html.escape(c)}</li>" for c in result.conventions) + "</ul>")
    parts += [f"<p class='warning'>warning: {html.escape(w)}</p>" for w in result.warnings]
    return "".join(parts) + "</section>"


def _failed(analysis, message: str) -> str:
    return (
        f"<section id='{analysis.name}'><h2>{analysis.name}</h2><p class='warning'>not computed: "
        f"{html.escape(message)}</p></section>"
    )


def _plain(value) -> str:
    from .. import jsonio

    return jsonio.dumps(value, indent=1)


def _page(lens, sections: list[str]) -> str:
    p = paraxial(lens)
    rows = [
        ("lens", f"{lens.name}: {lens.description}"),
        ("source", lens.source),
        ("hash", lens.hash),
        ("EFL", f"{p.efl_mm:.6g} mm at {p.wavelength_nm:g} nm"),
        ("f-number (EFL/EPD)", f"{p.f_number:.4g}"),
        ("working f-number", f"{p.working_f_number:.4g}"),
        ("half field", f"{lens.field_deg:g} deg"),
        ("wavelengths", ", ".join(f"{w:g}" for w in lens.wavelengths_nm) + " nm"),
        ("image plane from paraxial focus", f"{p.image_offset_mm:.6g} mm"),
    ]
    table = "".join(f"<tr><th>{html.escape(k)}</th><td>{html.escape(str(v))}</td></tr>" for k, v in rows)
    contents = " · ".join(f"<a href='#{a}'>{a}</a>" for a in ANALYSES)
    return (
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(lens.name)}: lens report</title>"
        f"<style>{STYLE}</style></head><body><h1>{html.escape(lens.name)}: lens report</h1><table>{table}</table>"
        f"<p>{contents}</p>{''.join(sections)}<p>solas-mi {installed_version()}</p></body></html>\n"
    )
