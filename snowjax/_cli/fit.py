"""`snowjax fit plate|tire|wheel`: calibrate parameters against measurements in a CSV file.

CSV files: comma-separated, one header line naming the columns, then one row per
measurement.  Lines starting with `#` and blank lines are ignored; extra columns are
ignored.  Column names (SI units unless stated):

- `plate`: `sinkage_m` [m], `pressure_Pa` [Pa] (or `pressure_kPa` [kPa]), and
  `plate_size_m` [m] (b of eq. 2.1/2.4; or give `--plate-size`).  The thesis's Table 2.1
  (`snowjax/data/table_2_1.csv`) has this layout: `--data .../table_2_1.csv
  --plate-size 0.23`.
- `tire`: `load_kN` [kN], `cs`, `ca` [kN/rad], `mux`, `muy`, `e1` [-] — the layout and
  units of the thesis's Table 3.2 (`snowjax/data/table_3_2.csv`).
- `wheel`: `load_N` [N], `slip` [-], and at least one of `sinkage_m` [m],
  `drawbar_pull_N` [N], `motion_resistance_N` [N].  The wheel is `--diameter`/`--width`;
  the snow parameters named by `--fit` are fitted (starting from the `--p-w`, `--z-w`,
  ... values), the others are held at those values (defaults: the thesis's fresh snow,
  `WongSnow.thesis_fresh_snow()`).  Other terrains: `--terrain bekker|reece|layered`
  with `--preset` and the parameter options of `snowjax sweep` (`--n`, `--k-c`,
  `--k-phi`, `--k-c-prime`, `--k-phi-prime`, `--unit-weight`, `--cohesion`, `--tan-phi`,
  `--shear-modulus`, `--set top.p_w=...`); `--distribution wong-reece` with `--c1`,
  `--c2`, `--c3`.  `--fit` then names any of their leaves (`k_phi,n,c1`, `top.p_w`);
  it is required for these terrains.

Output: a table (or `--json`: params, stderr, units, sse, residuals, warnings,
correlation, condition_number, dof, success, num_steps).  A malformed file (missing
column, text in a number, empty file, NaN, wrong field count, value out of range) prints
one message naming the file, the line and the problem, and exits with status 2; so do a
fit that fails (no finite SSE, fewer valid points than parameters) and options that would
do nothing (`--plate-size` with `--law wong` or a `plate_size_m` column, `--cohesion` /
`--unit-weight` without `--law reece`).  A UTF-8 byte-order mark is accepted; the two
pressure columns together are refused.
JAX is imported lazily, inside `run`, and runs in float64.
"""

from __future__ import annotations

import json
import math
import pathlib
import sys
from typing import Any

_PLATE_HELP = "columns: sinkage_m, pressure_Pa (or pressure_kPa), plate_size_m (or --plate-size)"
_TIRE_HELP = "columns: load_kN, cs, ca [kN/rad], mux, muy, e1 (the units of thesis Table 3.2)"
_WHEEL_HELP = (
    "columns: load_N, slip and at least one of sinkage_m, drawbar_pull_N, motion_resistance_N"
)

# Allowed range per column: (predicate, description).
_RANGES = {
    "sinkage_m": (lambda x: x >= 0, ">= 0 m"),
    "plate_size_m": (lambda x: x > 0, "> 0 m"),
    "load_kN": (lambda x: x > 0, "> 0 kN"),
    "cs": (lambda x: x > 0, "> 0 kN/rad"),
    "ca": (lambda x: x > 0, "> 0 kN/rad"),
    "e1": (lambda x: 0 < x < 0.5, "in (0, 0.5)"),
    "load_N": (lambda x: x > 0, "> 0 N"),
    "slip": (lambda x: -1 <= x <= 1, "in [-1, 1]"),
}


# Columns that give the same quantity in different units: a file may hold only one of each.
_ALIASES = (("pressure_Pa", "pressure_kPa"),)
# The largest magnitude whose square is finite in float64 (about 1.34e154): larger values
# overflow the fits' arithmetic (squares, powers).
_MAX_MAGNITUDE = math.sqrt(sys.float_info.max)


class DataError(Exception):
    """A malformed data file; the message names the file, the line and the problem."""


def read_csv(path, required, optional=(), one_of=()) -> dict:
    """Read numeric columns from a CSV file, with messages that name file, line, problem.

    - `required`: columns that must be present.
    - `optional`: columns read when present.
    - `one_of`: groups (tuples); at least one column of each group must be present.

    A UTF-8 byte-order mark (as spreadsheet programs write) is accepted.  Two columns of
    `_ALIASES` (the same quantity in two units) are refused, as are values whose square
    overflows float64.  Returns a dict column -> list of floats (only the columns asked
    for and present).  Raises `DataError`.
    """
    path = pathlib.Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as e:
        raise DataError(f"{path}: cannot read the file ({e.strerror or e})") from None
    except UnicodeDecodeError:
        raise DataError(f"{path}: not a UTF-8 text file") from None
    lines = [
        (k, ln.strip())
        for k, ln in enumerate(text.splitlines(), start=1)
        if ln.strip() and not ln.lstrip().startswith("#")
    ]
    expected = ", ".join(list(required) + [" | ".join(g) for g in one_of] + list(optional))
    if not lines:
        raise DataError(f"{path}: the file is empty (expected a header line with: {expected})")
    header_line, header = lines[0]
    names = [h.strip() for h in header.split(",")]
    dup = sorted({h for h in names if names.count(h) > 1})
    if dup:
        raise DataError(f"{path}: line {header_line} (header): duplicate column(s) {dup}")
    missing = [c for c in required if c not in names]
    missing += [" or ".join(g) for g in one_of if not any(c in names for c in g)]
    if missing:
        raise DataError(
            f"{path}: line {header_line} (header): missing column(s) "
            f"{', '.join(repr(m) for m in missing)}; expected columns: {expected}; "
            f"found: {', '.join(names)}"
        )
    for group in _ALIASES:
        both = [c for c in group if c in names]
        if len(both) > 1:
            raise DataError(
                f"{path}: line {header_line} (header): columns "
                f"{' and '.join(repr(c) for c in both)} give the same quantity in different "
                "units; keep one of them"
            )
    known = set(required) | set(optional) | {c for g in one_of for c in g}
    wanted = [c for c in names if c in known]
    cols = {c: [] for c in wanted}
    rows = lines[1:]
    if not rows:
        raise DataError(f"{path}: no data rows after the header (line {header_line})")
    for row_no, (line_no, ln) in enumerate(rows, start=1):
        fields = [x.strip() for x in ln.split(",")]
        where = f"{path}: line {line_no} (data row {row_no})"
        if len(fields) != len(names):
            raise DataError(f"{where}: expected {len(names)} fields, got {len(fields)}")
        for c in wanted:
            raw = fields[names.index(c)]
            if raw == "":
                raise DataError(f"{where}, column {c!r}: empty value")
            try:
                x = float(raw)
            except ValueError:
                raise DataError(f"{where}, column {c!r}: {raw!r} is not a number") from None
            if not math.isfinite(x):
                raise DataError(f"{where}, column {c!r}: {raw!r} is not a finite number")
            if abs(x) >= _MAX_MAGNITUDE:
                raise DataError(
                    f"{where}, column {c!r}: {raw} is too large for float64 arithmetic (its "
                    f"square overflows; keep values well below {_MAX_MAGNITUDE:.3g})"
                )
            if c in _RANGES and not _RANGES[c][0](x):
                raise DataError(
                    f"{where}, column {c!r}: {raw} is out of range (must be {_RANGES[c][1]})"
                )
            cols[c].append(x)
    return cols


def register(sub) -> None:
    """Add `fit plate|tire|wheel` to the `snowjax` argument parser."""
    p = sub.add_parser(
        "fit",
        help="calibrate parameters against measurements in a CSV file",
        description="Least-squares calibration with standard errors and identifiability "
        "warnings: plate-sinkage laws (2.1, 2.3, 2.4), the tire load functions "
        "(3.17)-(3.21), or snow parameters through the wheel equilibrium (4.14).",
        epilog=f"plate: {_PLATE_HELP}.  tire: {_TIRE_HELP}.  wheel: {_WHEEL_HELP}.  "
        "Lines starting with # are comments; extra columns are ignored.",
    )
    kinds = p.add_subparsers(dest="fit_kind", required=True)

    _plate_parser(kinds)
    _tire_parser(kinds)
    _wheel_parser(kinds)
    p.set_defaults(run=run)


def _common(q) -> None:
    """The options every kind of fit has: the data file and JSON output."""
    q.add_argument(
        "--data",
        required=True,
        type=pathlib.Path,
        metavar="FILE.csv",
        help="CSV file with a header line (see the column list above)",
    )
    q.add_argument("--json", action="store_true", help="print the result as JSON")


def _plate_parser(kinds) -> None:
    """`snowjax fit plate`."""
    plate = kinds.add_parser(
        "plate",
        help="fit a pressure-sinkage law to plate-sinkage data",
        description=f"Fit Bekker (2.1), Wong (2.3) or Reece (2.4) to a plate test.  {_PLATE_HELP}.",
    )
    _common(plate)
    plate.add_argument("--law", choices=("bekker", "wong", "reece"), default="bekker")
    plate.add_argument(
        "--plate-size",
        type=float,
        default=None,
        metavar="B",
        help="b [m] for every row when the file has no plate_size_m column",
    )
    plate.add_argument(
        "--cohesion",
        type=float,
        default=None,
        help="c [Pa], to report Reece's k'_c (two or more plate sizes)",
    )
    plate.add_argument(
        "--unit-weight",
        type=float,
        default=None,
        help="gamma_s [N/m^3], to report Reece's k'_phi (two or more sizes)",
    )
    plate.set_defaults(run=run)


def _tire_parser(kinds) -> None:
    """`snowjax fit tire`."""
    tire = kinds.add_parser(
        "tire",
        help="fit the tire load functions (3.17)-(3.21)",
        description=f"Fit (3.17)-(3.21) to FEA or test data like thesis Table 3.2.  {_TIRE_HELP}.",
    )
    _common(tire)
    tire.set_defaults(run=run)


def _wheel_parser(kinds) -> None:
    """`snowjax fit wheel`."""
    wheel = kinds.add_parser(
        "wheel",
        help="fit snow parameters through the wheel equilibrium (4.14)",
        description=f"Fit WongSnow parameters to sinkage / drawbar pull / motion resistance "
        f"versus slip.  {_WHEEL_HELP}.  Unfitted snow parameters are held at the given "
        "values (defaults: the thesis's fresh snow).",
    )
    _common(wheel)
    wheel.add_argument(
        "--fit",
        default=None,
        help="comma-separated parameters to fit: WongSnow fields (p_w, z_w, "
        "cohesion, tan_phi, shear_modulus; default p_w,z_w,tan_phi) or, with "
        "--terrain / --distribution, any of their leaves (e.g. k_phi,n,c1)",
    )
    wheel.add_argument(
        "--terrain",
        choices=("wong", "bekker", "reece", "layered"),
        default="wong",
        help="terrain law (default %(default)s)",
    )
    wheel.add_argument(
        "--preset", default=None, help="preset of the terrain (as `snowjax sweep --preset`)"
    )
    wheel.add_argument("--diameter", type=float, default=0.736, help="wheel diameter D [m]")
    wheel.add_argument("--width", type=float, default=0.235, help="wheel width b [m]")
    wheel.add_argument("--p-w", type=float, default=None, help="p_w [Pa] (start or fixed value)")
    wheel.add_argument("--z-w", type=float, default=None, help="z_w [m]")
    wheel.add_argument("--cohesion", type=float, default=None, help="c [Pa]")
    wheel.add_argument("--tan-phi", type=float, default=None, help="tan(phi) [-]")
    wheel.add_argument("--shear-modulus", type=float, default=None, help="K [m]")
    for option, unit in (
        ("n", "-"),
        ("k-c", "N/m^(n+1)"),
        ("k-phi", "N/m^(n+2)"),
        ("k-c-prime", "-"),
        ("k-phi-prime", "-"),
        ("unit-weight", "N/m^3"),
    ):
        wheel.add_argument(
            f"--{option}",
            type=float,
            default=None,
            help=f"{option.replace('-', '_')} [{unit}] (start or fixed value)",
        )
    wheel.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="any terrain leaf by name, e.g. top.p_w=30e3 (repeatable)",
    )
    wheel.add_argument(
        "--distribution",
        choices=("none", "wong-reece"),
        default="none",
        help="stress distribution (default %(default)s)",
    )
    for option in ("c1", "c2", "c3"):
        wheel.add_argument(
            f"--{option}",
            type=float,
            default=None,
            help=f"Wong-Reece {option} [-] (start or fixed value)",
        )
    wheel.add_argument("--shear", choices=("classic", "simplified", "none"), default="classic")
    wheel.add_argument("--max-steps", type=int, default=100, help="Levenberg-Marquardt steps")
    wheel.set_defaults(run=run)


def _fail(message: str) -> int:
    print(f"snowjax fit: error: {message}", file=sys.stderr)
    return 2


def run(args) -> int:
    """Run `snowjax fit <kind>`; returns the exit code (0 ok, 2 bad data or arguments)."""
    kind = getattr(args, "fit_kind", None)
    path = args.data
    unused = _unused_options(kind, args)
    if unused:
        return _fail(unused)
    try:
        if kind == "plate":
            cols = read_csv(
                path,
                ["sinkage_m"],
                optional=["plate_size_m"],
                one_of=[("pressure_Pa", "pressure_kPa")],
            )
        elif kind == "tire":
            cols = read_csv(path, ["load_kN", "cs", "ca", "mux", "muy", "e1"])
        elif kind == "wheel":
            cols = read_csv(
                path,
                ["load_N", "slip"],
                one_of=[("sinkage_m", "drawbar_pull_N", "motion_resistance_N")],
            )
        else:  # pragma: no cover - argparse requires a kind
            return _fail("choose one of: plate, tire, wheel")
    except DataError as e:
        return _fail(str(e))

    import jax

    jax.config.update("jax_enable_x64", True)
    import numpy as np

    from .._fit.plate import fit_plate_sinkage
    from .._fit.tire import fit_tire_coefficients
    from .._fit.wheel import fit_parameter_names, fit_wheel
    from .._wheel.geometry import RigidWheel
    from .._wheel.model import ContactModel

    try:
        if kind == "plate":
            if "pressure_Pa" in cols:
                pressure = np.array(cols["pressure_Pa"])
            else:
                pressure = 1e3 * np.array(cols["pressure_kPa"])
            if "plate_size_m" in cols:
                if args.plate_size is not None:
                    return _fail(
                        f"{path}: --plate-size and the plate_size_m column both give the plate "
                        "size; keep one of them"
                    )
                size = np.array(cols["plate_size_m"])
            else:
                size = args.plate_size
            if args.law != "wong" and size is None:
                return _fail(
                    f"{path}: law {args.law!r} needs the plate size b: add a plate_size_m "
                    "column or pass --plate-size"
                )
            result = fit_plate_sinkage(
                np.array(cols["sinkage_m"]), pressure, args.law, size,
                cohesion=args.cohesion, unit_weight=args.unit_weight,
            )  # fmt: skip
        elif kind == "tire":
            result = fit_tire_coefficients(
                *(np.array(cols[c]) for c in ("load_kN", "cs", "ca", "mux", "muy", "e1"))
            )
        else:
            snow, distribution = _wheel_model(args)
            fit_text = args.fit
            if fit_text is None:
                if not (args.terrain == "wong" and distribution is None):
                    names = ", ".join(fit_parameter_names(snow, distribution))
                    raise ValueError(f"give --fit: the parameters to fit, among {names}")
                fit_text = "p_w,z_w,tan_phi"
            names = tuple(s.strip() for s in fit_text.split(",") if s.strip())
            measured: dict[str, Any] = {q: np.array(cols[c]) for q, c in (
                ("sinkage", "sinkage_m"), ("drawbar_pull", "drawbar_pull_N"),
                ("motion_resistance", "motion_resistance_N")) if c in cols}  # fmt: skip
            result = fit_wheel(
                RigidWheel(args.diameter, args.width),
                ContactModel(snow, distribution, args.shear),
                np.array(cols["load_N"]), np.array(cols["slip"]), measured,
                fit=names, max_steps=args.max_steps,
            )  # fmt: skip
    except (ValueError, TypeError) as e:
        return _fail(f"{path}: {e}")

    if args.json:
        out = {"command": f"fit {kind}", "data": str(path), **result.to_dict()}
        print(json.dumps(out, indent=2))
    else:
        print(f"data: {path}")
        print(result.table())
    return 0


def _unused_options(kind, args) -> str | None:
    """The message for options that would do nothing in this combination (None if none)."""
    if kind == "plate":
        if args.law == "wong" and args.plate_size is not None:
            return "--plate-size is not used by --law wong (Wong's law (2.3) has no plate size)"
        reece_only = [f"--{o}" for o, v in (("cohesion", args.cohesion),
                      ("unit-weight", args.unit_weight)) if v is not None]  # fmt: skip
        if reece_only and args.law != "reece":
            verb = "applies" if len(reece_only) == 1 else "apply"
            return (
                f"{' and '.join(reece_only)} only {verb} with --law reece (for its k'_c, "
                f"k'_phi); got --law {args.law}"
            )
    if kind == "wheel" and args.max_steps < 1:
        return f"--max-steps must be >= 1 (Levenberg-Marquardt steps), got {args.max_steps}"
    return None


def _wheel_model(args):
    """(terrain, distribution) of `fit wheel` from its options (start / fixed values)."""
    from .._terrain.wong import WongSnow
    from .._wheel.distribution import WongReece
    from .sweep import terrain_from_options

    wong_only = {"p_w": args.p_w, "z_w": args.z_w}
    shared = {"cohesion": args.cohesion, "tan_phi": args.tan_phi,
              "shear_modulus": args.shear_modulus}  # fmt: skip
    other = {"n": args.n, "k_c": args.k_c, "k_phi": args.k_phi, "k_c_prime": args.k_c_prime,
             "k_phi_prime": args.k_phi_prime, "unit_weight": args.unit_weight}  # fmt: skip
    given = {k: v for k, v in {**wong_only, **shared, **other}.items() if v is not None}
    options = {("terrain", k): f"--{k.replace('_', '-')}" for k in given}
    for item in args.set:
        name, sep, text = item.partition("=")
        name = name.strip()
        try:
            value = float(text)
        except ValueError:
            value = None
        if not sep or not name or value is None:
            raise ValueError(f"--set {item!r}: expected NAME=VALUE, e.g. top.p_w=30e3")
        if name in given:
            raise ValueError(f"--set {item!r}: {name} is given twice")
        given[name] = value
        options[("terrain", name)] = f"--set {name}"
    if (
        args.terrain == "wong"
        and args.preset in (None, "thesis")
        and set(given) <= set(wong_only) | set(shared)
    ):
        # The thesis's fresh snow with the given values replacing its own.
        base = WongSnow.thesis_fresh_snow()
        snow = WongSnow(**{k: float(given.get(k, getattr(base, k))) for k in (
            "p_w", "z_w", "cohesion", "tan_phi", "shear_modulus")})  # fmt: skip
    else:
        snow = terrain_from_options(args.terrain, args.preset, None, given, options)
    coefficients = {"c1": args.c1, "c2": args.c2, "c3": args.c3}
    if args.distribution == "none":
        bad = [f"--{k}" for k, v in coefficients.items() if v is not None]
        if bad:
            raise ValueError(f"{', '.join(bad)} only apply with --distribution wong-reece")
        return snow, None
    ref = WongReece.reference()
    distribution = WongReece(
        **{k: float(getattr(ref, k)) if v is None else v for k, v in coefficients.items()}
    )
    return snow, distribution
