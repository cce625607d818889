"""What a figure module of `snowjax reproduce` declares: its figures and report tables.

A figure is a function `draw(ctx: Context) -> FigureResult` decorated with `@figure(...)`,
which turns it into a `FigureSpec` (thesis number, title, caption, equations, the function).
A report section that is a table rather than a figure is declared the same way with
`@table(...)`.  The specs are listed, one line each, in `registry.py`.
"""

from __future__ import annotations

import dataclasses
import pathlib
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["Context", "FigureResult", "FigureSpec", "TableSpec", "figure", "table"]


@dataclasses.dataclass
class Context:
    """Run-wide state handed to every figure and table function.

    - `out`: the output directory.
    - `small`: coarse grids (for tests).
    - `cache`: results shared between figures (e.g. one wheel sweep for Figs 4.7, 4.8).
    - `extra_files`: files a figure writes besides its PNG and CSV (listed by the driver).
    """

    out: pathlib.Path
    small: bool
    cache: dict = dataclasses.field(default_factory=dict)
    extra_files: list[pathlib.Path] = dataclasses.field(default_factory=list)

    @property
    def n_curve(self) -> int:
        return 11 if self.small else 101

    @property
    def n_wheel_slips(self) -> int:
        return 5 if self.small else 41

    @property
    def n_sigma(self) -> int:
        return 24 if self.small else 400


@dataclasses.dataclass
class FigureResult:
    """What a figure function returns.

    - `figure`: the matplotlib figure.
    - `columns`, `rows`: the numbers behind it (written to the CSV; thinned in the report).
    - `comparison`: markdown paragraph, "comparison with the thesis", with our numbers.
    - `table_columns`, `table_rows`: an optional different table for the report (e.g. the
      Table 3.2 comparison), instead of the thinned CSV data.
    - `verdict`: one line for the report's overview table.
    """

    figure: Figure
    columns: Sequence[str]
    rows: list
    comparison: str
    table_columns: Sequence[str] | None = None
    table_rows: list | None = None
    verdict: str = ""


@dataclasses.dataclass(frozen=True)
class FigureSpec:
    """One figure of the thesis: number ("4.7"), title, caption, equations, draw function."""

    number: str
    title: str
    caption: str
    equations: tuple[str, ...]
    draw: Callable[[Context], FigureResult]

    @property
    def stem(self) -> str:
        return "fig_" + self.number.replace(".", "_")


@dataclasses.dataclass(frozen=True)
class TableSpec:
    """A report section that is a table, not a figure: markdown text and one CSV.

    - `name`: how a failure is listed in the report ("Tables 4.3-4.6").
    - `title`: the section's title (progress bar; heading when it fails).
    - `stem`: the CSV's file name without `.csv`.
    - `make`: `make(ctx) -> (markdown, columns, rows)`.
    """

    name: str
    title: str
    stem: str
    make: Callable[[Context], tuple[str, Sequence[str], list]]


def figure(
    number: str, title: str, caption: str, equations: tuple[str, ...]
) -> Callable[[Callable[[Context], FigureResult]], FigureSpec]:
    """Decorator: the draw function below becomes the `FigureSpec` of figure `number`."""

    def wrap(draw: Callable[[Context], FigureResult]) -> FigureSpec:
        return FigureSpec(number, title, caption, equations, draw)

    return wrap


def table(
    name: str, title: str, stem: str
) -> Callable[[Callable[[Context], tuple[str, Sequence[str], list]]], TableSpec]:
    """Decorator: the function below becomes the `TableSpec` of a report table."""

    def wrap(make: Callable[[Context], tuple[str, Sequence[str], list]]) -> TableSpec:
        return TableSpec(name, title, stem, make)

    return wrap
