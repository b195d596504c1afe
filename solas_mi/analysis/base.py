"""The shape every lens analysis shares: a frozen `Result` holding what it was computed from (the lens,
its inputs, the conventions its numbers follow, warnings) and its numbers; `table()`, the numbers as
rows under named columns (units in the names) for CSV and JSON; `plot()`, a matplotlib figure; and
`write(png)`, the PNG with its JSON and CSV beside it, written together or not at all.

A new analysis subclasses `Result` (a frozen, keyword-only dataclass adding its arrays), implements
`table()` and `plot()`, ends its function with `YourResult.of(lens, "its-name", inputs=..., conventions=...,
warnings=..., its arrays...)` (the header every result shares, filled from the lens), and registers the
function in `registry.ANALYSES`.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Self

from .. import jsonio
from ..errors import SolasError


@dataclass(frozen=True)
class Table:
    """The numbers of an analysis as rows under named columns.

    Parameters
    ----------
    columns : tuple of str
        The column names, each ending with its unit (`_deg`, `_mm`, `_um`, `_cy_mm`, `_waves`; no unit: a
        ratio).
    rows : tuple of tuple
        The rows, one value per column: a number, or None where it is undefined (a ray that did not arrive).
    summary : dict
        Named numbers of the whole result (MTF50 per field, RMS radii), JSON-ready.
    """

    columns: tuple[str, ...]
    rows: tuple[tuple[Any, ...], ...]
    summary: dict = field(default_factory=dict)

    def csv(self) -> str:
        """The rows as CSV text.

        Returns
        -------
        str
            A header of the column names, then one line per row; an undefined value is an empty cell,
            a float at full precision.
        """
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(self.columns)
        for row in self.rows:
            writer.writerow(["" if v is None else _cell(v) for v in row])
        return out.getvalue()


def defined(value) -> float | None:
    """A number as a float, None where it is undefined (NaN: a ray that did not arrive, a curve that
    never crosses), as the tables hold it."""
    value = float(value)
    return None if math.isnan(value) else value


def _cell(value: Any) -> Any:
    """A number at full precision (repr of a float), anything else as it is."""
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ("inf" if value > 0 else "-inf")
    return value


@dataclass(frozen=True, kw_only=True)
class Result:
    """What every analysis returns (a subclass adds its numbers as fields).

    Parameters
    ----------
    name : str
        The analysis, a name of `registry.ANALYSES`.
    lens : str
        The lens's name.
    lens_hash : str
        The lens's hash (`Lens.hash`).
    inputs : dict
        The options it was computed with, as resolved (defaults filled in).
    conventions : tuple of str
        What the numbers mean: directions, units, references.
    warnings : tuple of str
        What may make the numbers less than they seem (a vignetted pupil, a coarse grid).
    """

    name: str
    lens: str
    lens_hash: str
    inputs: dict  # the options it was computed with, as resolved (defaults filled in)
    conventions: tuple[str, ...]  # what the numbers mean: directions, units, references
    warnings: tuple[str, ...] = ()

    @classmethod
    def of(cls, lens, name: str, *, inputs: dict, conventions, warnings=(), **numbers) -> Self:
        """The result of the analysis `name` of `lens`: the header every analysis shares (the lens's name and
        hash, `inputs`, `conventions` and `warnings` as tuples) and the subclass's `numbers`.

        Parameters
        ----------
        lens : Lens
            The lens analysed.
        name : str
            The analysis, a name of `registry.ANALYSES`.
        inputs : dict
            The options it was computed with, as resolved (defaults filled in).
        conventions : sequence of str
            What the numbers mean.
        warnings : sequence of str
            What may make the numbers less than they seem.
        **numbers
            The subclass's own fields.

        Returns
        -------
        Result
            An instance of the subclass it is called on.
        """
        return cls(
            name=name,
            lens=lens.name,
            lens_hash=lens.hash,
            inputs=inputs,
            conventions=tuple(conventions),
            warnings=tuple(warnings),
            **numbers,
        )

    def table(self) -> Table:
        """The numbers as a table.

        Returns
        -------
        Table
            Rows under columns named with their units, and the summary numbers.
        """
        raise NotImplementedError

    def plot(self):
        """The figure of the analysis, made without pyplot (no window, no global state).

        Returns
        -------
        matplotlib.figure.Figure
            Its panels with axes labelled with units and legends, titled with the lens and the analysis.
        """
        raise NotImplementedError

    def as_dict(self) -> dict:
        """The whole result as JSON-ready values.

        Returns
        -------
        dict
            The analysis, lens, inputs, conventions, warnings, summary, columns and rows (undefined values
            None).
        """
        t = self.table()
        return {
            "analysis": self.name,
            "lens": self.lens,
            "lens_hash": self.lens_hash,
            "inputs": self.inputs,
            "conventions": list(self.conventions),
            "warnings": list(self.warnings),
            "summary": t.summary,
            "columns": list(t.columns),
            "rows": [list(r) for r in t.rows],
        }

    def write(self, png: str | Path) -> tuple[Path, Path, Path]:
        """Write the figure and its numbers beside it, all three replaced together or none.

        Parameters
        ----------
        png : str or Path
            The figure's path, ending in .png; the .json (`as_dict`, strict JSON) and .csv (`table`) go
            beside it.

        Returns
        -------
        tuple of Path
            The PNG, JSON and CSV paths.
        """
        return write_result(self, png)


def output_paths(png: str | Path) -> tuple[Path, Path, Path]:
    """The checked PNG, JSON and CSV paths of an analysis written to `png` (which must end in .png)."""
    from ..outputs import check_target

    png = Path(png)
    if png.suffix.lower() != ".png":
        raise SolasError(f"output {str(png)!r} must end in .png (its .json and .csv are written beside it)")
    return check_target(png), check_target(png.with_suffix(".json")), check_target(png.with_suffix(".csv"))


def write_result(result: Result, png: str | Path) -> tuple[Path, Path, Path]:
    """`Result.write`: the figure and both tables, through temporary files renamed together."""
    from ..outputs import written_together
    from .figures import save

    paths = output_paths(png)
    text = jsonio.dumps(result.as_dict(), indent=1)  # before any file: a NaN is refused here, nothing written
    table = result.table().csv()
    figure = result.plot()
    with written_together(*paths) as (tmp_png, tmp_json, tmp_csv):
        save(figure, tmp_png)
        Path(tmp_json).write_text(text + "\n", encoding="utf-8")
        Path(tmp_csv).write_text(table, encoding="utf-8")
    return paths
