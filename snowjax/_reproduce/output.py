"""CSV files and markdown tables of `snowjax reproduce`: number formatting and writing."""

from __future__ import annotations

import csv
import math
import pathlib

import numpy as np


def fmt(x) -> str:
    """A number as text, 4 significant digits; strings pass through, None is empty."""
    if isinstance(x, str):
        return x
    if x is None:
        return ""
    x = float(x)
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    if x == 0:
        return "0"
    return f"{x:.4g}"


def thin(rows: list, n: int = 12) -> list:
    """At most `n` rows, evenly spaced, first and last kept (the report's tables)."""
    if len(rows) <= n:
        return rows
    idx = np.unique(np.round(np.linspace(0, len(rows) - 1, n)).astype(int))
    return [rows[i] for i in idx]


def cell(x) -> str:
    """One markdown table cell."""
    return fmt(x).replace("|", "\\|")


def md_table(columns, rows) -> str:
    """A markdown table."""
    lines = ["| " + " | ".join(cell(c) for c in columns) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        lines.append("| " + " | ".join(cell(x) for x in r) + " |")
    return "\n".join(lines)


def write_csv(path: pathlib.Path, columns, rows) -> None:
    """A CSV file; numbers written with `repr(float(x))` (round-trips exactly)."""
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(columns)
        for r in rows:
            w.writerow([x if isinstance(x, str) else repr(float(x)) for x in r])
