"""`snowjax reproduce`: regenerate the thesis's figures and `report.md`.

`snowjax reproduce [--out DIR] [--small]` runs `snowjax.reproduce`
(snowjax/_reproduce/registry.py):
one PNG and one CSV per reproduced figure of Sankapalli (2004), the wheel sweep
`wheel_sweep.csv` of Figs 4.7/4.8, `derivative_tables.csv` (Tables 4.3–4.6 against
autodiff) and `report.md`, which shows every figure with its caption, equations, numbers
and a comparison with the thesis.  JAX is imported lazily (so `--help` is fast) and runs
in float64.
"""

from __future__ import annotations

import os
import pathlib
import sys


def register(sub) -> None:
    """Add the `reproduce` subcommand to the `snowjax` argument parser."""
    rep = sub.add_parser(
        "reproduce",
        help="regenerate the thesis's figures, their data and report.md",
        description="Regenerate the figures of Sankapalli (2004) as PNG files, the numbers "
        "behind them as CSV files, and report.md comparing each figure with the thesis.",
    )
    rep.add_argument(
        "--out",
        default="snowjax-output",
        help="output directory (default: ./snowjax-output)",
    )
    rep.add_argument(
        "--small",
        action="store_true",
        help="reduced grid sizes (for tests; same files, coarser curves)",
    )
    rep.set_defaults(run=run, parser=rep)


def _output_dir(text: str) -> pathlib.Path:
    """The output directory, created; ValueError naming the problem if it cannot be."""
    if not text.strip():
        raise ValueError("--out must name a directory, got ''")
    out = pathlib.Path(text)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {text}: exists and is not a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ValueError(f"--out {text}: cannot create the directory ({err.strerror})") from None
    if not os.access(out, os.W_OK):
        raise ValueError(f"--out {text}: the directory is not writable")
    return out


def run(args) -> int:
    """Run the reproduction; print a summary table and the path of report.md."""
    import time

    try:
        args.out = _output_dir(args.out)
    except ValueError as err:
        print(f"snowjax reproduce: error: {err}", file=sys.stderr)
        return 2

    import jax

    jax.config.update("jax_enable_x64", True)
    from rich.console import Console
    from rich.table import Table

    from .._reproduce.registry import FIGURES, reproduce

    console = Console()
    start = time.perf_counter()
    files = reproduce(args.out, small=args.small, progress=True)
    elapsed = time.perf_counter() - start
    written = {f.name for f in files}

    table = Table(title=f"snowjax reproduce: {len(FIGURES)} figures of Sankapalli (2004)")
    table.add_column("figure", justify="right")
    table.add_column("content")
    table.add_column("files")
    missing = []
    for spec in FIGURES:
        ok = f"{spec.stem}.png" in written and f"{spec.stem}.csv" in written
        if not ok:
            missing.append(spec.number)
        table.add_row(
            spec.number,
            spec.title,
            f"{spec.stem}.png, .csv" if ok else "[red]FAILED (see report.md)[/red]",
        )
    console.print(table)
    extra = [n for n in ("wheel_sweep.csv", "derivative_tables.csv") if n in written]
    console.print(f"Also written: {', '.join(extra)}.")
    report = pathlib.Path(args.out) / "report.md"
    console.print(
        f"{len(files)} files in {elapsed:.1f} s. Report: [bold]{report}[/bold]", soft_wrap=True
    )
    if missing:
        console.print(f"[red]Figures not produced: {', '.join(missing)}[/red]")
        return 1
    return 0
