"""`snowjax validate`: compare the models with measured snow data and write `report.md`.

`snowjax validate [--out DIR] [--include-uncertain] [--wheel-load N] [--tyre-width M]` runs
`snowjax.validate` (snowjax/_validate/): Shoop (2001), ERDC/CRREL TR-01-16 Table 11
(sinkage and snow resistance coefficient of a leading tyre) modelled by the CRREL
shallow-snow model, Richmond (2.23), Van Es (2.26), the chapter-4 wheel and the deflecting
tyre on Wong snow and Bekker (2.24/2.25): predictions (no parameter from the rows) and
calibrations (fitted within cited bounds, cross-validated by snow with the fit repeated
per fold), with each model's skill against the mean; plus the CRM-1 worked examples of
CRREL 95-1.
Writes report.md, metrics.csv, predictions.csv, crrel_95_1_examples.csv and
predicted_vs_measured.png.  JAX is imported lazily and runs in float64.

`snowjax validate --single-wheel DIR` instead calibrates the wheel under slip angle on the
single-wheel sand tests in DIR (robomechanics/3d-terramechanics; `../shared/data/
3d-terramechanics` in this repository's CI) at beta = 0/30/60 deg and predicts 15/45 deg
(and 75 deg, extrapolation): writes single_wheel.md, single_wheel_<wheel>.png and
single_wheel_predictions.csv.
"""

from __future__ import annotations

import math
import pathlib
import sys


def register(sub) -> None:
    """Add the `validate` subcommand to the `snowjax` argument parser."""
    p = sub.add_parser(
        "validate",
        help="compare every model with measured snow data (Shoop 2001, CRREL 95-1)",
        description="Predictions and cross-validated calibrations of the snowjax models "
        "against measured sinkage and resistance in snow (Shoop 2001, ERDC/CRREL TR-01-16, "
        "Table 11) and the CRM-1 examples of CRREL 95-1; writes report.md, CSVs and a "
        "figure.",
    )
    p.add_argument(
        "--out",
        type=pathlib.Path,
        default=pathlib.Path("snowjax-validate"),
        help="output directory (default: ./snowjax-validate)",
    )
    p.add_argument(
        "--include-uncertain",
        action="store_true",
        help="also use the two Table 11 rows of uncertain tyre radius",
    )
    p.add_argument(
        "--wheel-load",
        type=float,
        default=None,
        help="wheel load [N] (default 6800, from CRREL 95-7 Table 2)",
    )
    p.add_argument(
        "--tyre-width",
        type=float,
        default=None,
        help="tyre width [m] (default 0.235, an assumption)",
    )
    p.add_argument(
        "--single-wheel",
        type=pathlib.Path,
        default=None,
        metavar="DIR",
        help="instead: calibrate and predict the single-wheel slip-angle sand tests in DIR "
        "(smooth_wheel.csv, grousered_wheel.csv of robomechanics/3d-terramechanics)",
    )
    p.set_defaults(run=run, parser=p)


def _fail(message: str) -> int:
    print(f"snowjax validate: error: {message}", file=sys.stderr)
    return 2


def run(args) -> int:
    """Run the validation; print the table and the path of report.md (exit code 0; 2 for
    a bad option, with one line on stderr)."""
    import time

    from .reproduce import _output_dir

    load, width = args.wheel_load, args.tyre_width
    if load is not None and not (math.isfinite(load) and load > 0):
        return _fail(f"--wheel-load must be a finite number > 0 (newtons), got {load}")
    if width is not None and not (math.isfinite(width) and 0 < width < 2):
        return _fail(f"--tyre-width must be in (0, 2) metres, got {width}")
    single = getattr(args, "single_wheel", None)
    try:
        args.out = _output_dir(str(args.out))
    except ValueError as err:
        return _fail(str(err))
    if single is not None:
        # Both data files are read and checked before JAX compiles anything.
        from .._validate.single_wheel import check_study_rows, load_single_wheel

        try:
            for wheel in ("smooth", "grousered"):
                check_study_rows(load_single_wheel(single, wheel))
        except (OSError, ValueError) as err:
            return _fail(f"--single-wheel: {err}")

    import jax

    jax.config.update("jax_enable_x64", True)
    from rich.console import Console

    if single is not None:
        from .._validate.single_wheel import write_single_wheel

        start = time.perf_counter()
        files = write_single_wheel(args.out, single, progress=True)
        Console().print(files[2].read_text(encoding="utf-8"), markup=False)
        print(f"{len(files)} files in {time.perf_counter() - start:.1f} s in {args.out}")
        return 0

    from .._validate.validate import (
        DEFAULT_TYRE_WIDTH,
        DEFAULT_WHEEL_LOAD,
        metrics_table_markdown,
        validate,
    )

    load = DEFAULT_WHEEL_LOAD if load is None else load
    width = DEFAULT_TYRE_WIDTH if width is None else width
    console = Console()
    start = time.perf_counter()
    result = validate(
        args.out,
        include_uncertain=args.include_uncertain,
        wheel_load=load,
        tyre_width=width,
        progress=True,
    )
    console.print(metrics_table_markdown(result.metrics, result.models), markup=False)
    for key, why in result.skipped.items():
        console.print(f"[yellow]skipped {key}: {why}[/yellow]")
    report = pathlib.Path(args.out) / "report.md"
    console.print(
        f"{len(result.files)} files in {time.perf_counter() - start:.1f} s. "
        f"Report: [bold]{report}[/bold]"
    )
    return 0
