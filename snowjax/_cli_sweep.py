"""`snowjax sweep`: chunked, resumable, sharded sweeps of the wheel equilibrium to disk.

    snowjax sweep --loads 2000:8000:13 --slips 0:0.9:10 --p-w 60e3,85.55e3 --out DIR

Value lists are `start:stop:num` (like `numpy.linspace`), a comma list, or one value.
By default the sweep is the grid parameter sets x loads x slips; parameter options
given as lists are zipped into parameter sets (equal lengths, or one value), or
combined into every combination with `--param-grid`.  `--list` zips loads, slips and
parameter lists instead of the grid (one point each).  The snow presets are the thesis's
Table 4.1 ratios for D = 0.736 m; when only `--p-w` is given the cohesion follows
c = 0.2165 p_w.  Running the same command again resumes an interrupted sweep; a
different sweep in the same `--out` is refused (use `--restart` to discard it).
See `snowjax.sweep`.
"""

from __future__ import annotations

import argparse
import itertools
import sys

_PARAMETERS = (
    # (option, field, object, unit)
    ("p-w", "p_w", "snow", "Pa"),
    ("z-w", "z_w", "snow", "m"),
    ("cohesion", "cohesion", "snow", "Pa"),
    ("tan-phi", "tan_phi", "snow", "-"),
    ("shear-modulus", "shear_modulus", "snow", "m"),
    ("diameter", "diameter", "wheel", "m"),
    ("width", "width", "wheel", "m"),
)


def register(sub) -> None:
    p = sub.add_parser(
        "sweep",
        help="chunked, resumable sweeps of the wheel equilibrium to disk",
        description=__doc__.split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--loads", default="2000:8000:13", help="wheel loads [N] (default %(default)s)")
    p.add_argument("--slips", default="0:0.9:10", help="driving slips [-] (default %(default)s)")
    p.add_argument("--shear", choices=("classic", "simplified", "none"), default="classic")
    p.add_argument(
        "--snow",
        choices=("thesis", "plate-rule"),
        default="thesis",
        help="preset snow: the thesis's fresh snow (p_w 85.55 kPa) or its plate-rule variant"
        " (p_w 12.92 kPa), Table 4.1 ratios for D = 0.736 m (default %(default)s)",
    )
    for option, field, obj, unit in _PARAMETERS:
        p.add_argument(
            f"--{option}",
            default=None,
            metavar="VALUES",
            help=f"override {obj} {field} [{unit}]; a list gives several parameter sets",
        )
    p.add_argument(
        "--param-grid",
        action="store_true",
        help="parameter sets: every combination of the parameter lists (default: zip them)",
    )
    p.add_argument(
        "--list",
        action="store_true",
        help="zip loads, slips and parameter lists (one point each) instead of the grid",
    )
    p.add_argument("--out", default="snowjax-sweep", help="output directory (default %(default)s)")
    p.add_argument("--chunk-size", type=int, default=8192, help="rows per chunk (default %(default)s)")
    p.add_argument(
        "--format", default="npz,csv", help="consolidated outputs: npz, csv, both or none"
        " (the chunk files are always kept) (default %(default)s)",
    )
    p.add_argument("--nodes-per-panel", type=int, default=None, help="quadrature nodes per panel")
    p.add_argument("--max-steps", type=int, default=64, help="Newton iteration limit")
    p.add_argument("--float32", action="store_true", help="solve in float32 (default float64)")
    p.add_argument("--restart", action="store_true", help="discard a sweep already in --out")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument(
        "--distributed",
        action="store_true",
        help="call jax.distributed.initialize() first (multi-host; chunk k is computed by"
        " process k %% process_count)",
    )
    p.add_argument("--coordinator", default=None, help="with --distributed: host:port of process 0")
    p.add_argument("--num-processes", type=int, default=None, help="with --distributed")
    p.add_argument("--process-id", type=int, default=None, help="with --distributed")
    p.set_defaults(run=run)


def _values(text: str, option: str):
    """`start:stop:num`, a comma list or one number -> 1-D float array."""
    import numpy as np

    text = text.strip()
    try:
        if ":" in text:
            parts = text.split(":")
            if len(parts) != 3:
                raise ValueError
            start, stop, num = float(parts[0]), float(parts[1]), parts[2]
            if not num.strip().isdigit() or int(num) < 1:
                raise ValueError
            return np.linspace(start, stop, int(num))
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise ValueError(
            f"--{option} {text!r}: expected start:stop:num (num a positive integer), a comma"
            " list of numbers, or one number"
        ) from None
    return np.asarray(values)


def _build(args):
    """The sweep's inputs from the options: (wheel, snow, loads, slips, formats)."""
    import numpy as np

    from ._params import THESIS_P_W, PLATE_RULE_P_W, RigidWheel, WongSnow

    loads = _values(args.loads, "loads")
    slips = _values(args.slips, "slips")
    given = {}
    for option, field, _, _ in _PARAMETERS:
        text = getattr(args, option.replace("-", "_"))
        if text is not None:
            given[field] = _values(text, option)
    options = {field: option for option, field, _, _ in _PARAMETERS}
    multi = [f for f, v in given.items() if v.size > 1]
    if args.param_grid and not args.list:
        # Every combination of the parameter lists (first option slowest).
        combos = np.array(list(itertools.product(*(given[f] for f in multi))))
        for j, f in enumerate(multi):
            given[f] = combos[:, j]
    elif not args.list and len({given[f].size for f in multi}) > 1:
        sizes = ", ".join(f"--{options[f]} has {given[f].size}" for f in multi)
        raise ValueError(
            f"parameter lists are zipped into parameter sets and must have the same length"
            f" (or one value): {sizes}; use --param-grid for every combination"
        )
    value = lambda f, default: (  # noqa: E731
        (given[f][0] if given[f].size == 1 else given[f]) if f in given else default
    )
    # The presets are the thesis's Table 4.1 ratios for D = 0.736 m; the cohesion follows
    # c = 0.2165 p_w when only p_w is overridden.
    preset_p_w = THESIS_P_W if args.snow == "thesis" else PLATE_RULE_P_W
    preset = WongSnow.thesis_fresh_snow(p_w=value("p_w", preset_p_w))
    snow = WongSnow(
        p_w=preset.p_w,
        z_w=value("z_w", preset.z_w),
        cohesion=value("cohesion", preset.cohesion),
        tan_phi=value("tan_phi", preset.tan_phi),
        shear_modulus=value("shear_modulus", preset.shear_modulus),
    )
    thesis = RigidWheel.thesis_tire()
    wheel = RigidWheel(
        diameter=value("diameter", thesis.diameter), width=value("width", thesis.width)
    )
    formats = tuple(f.strip() for f in args.format.split(",") if f.strip() and f.strip() != "none")
    for f in formats:
        if f not in ("npz", "csv"):
            raise ValueError(f"--format {args.format!r}: choose from npz, csv, none")
    return wheel, snow, loads, slips, formats


def run(args) -> int:
    try:
        if args.chunk_size < 1:
            raise ValueError(f"--chunk-size must be a positive integer, got {args.chunk_size}")
        import jax

        jax.config.update("jax_enable_x64", not args.float32)
        if args.distributed:
            jax.distributed.initialize(
                coordinator_address=args.coordinator,
                num_processes=args.num_processes,
                process_id=args.process_id,
            )
        from ._sweep import sweep

        wheel, snow, loads, slips, formats = _build(args)
        result = sweep(
            wheel,
            snow,
            loads,
            slips,
            shear=args.shear,
            out=args.out,
            chunk_size=args.chunk_size,
            grid=not args.list,
            progress=not args.no_progress,
            resume=not args.restart,
            formats=formats,
            nodes_per_panel=args.nodes_per_panel,
            max_steps=args.max_steps,
        )
    except ValueError as err:
        message = str(err).removeprefix("sweep: ")
        print(f"snowjax sweep: error: {message}", file=sys.stderr)
        return 2
    except OSError as err:  # disk full, permissions: the chunks written so far are kept
        print(
            f"snowjax sweep: error: {err}; fix it and run the same command again to resume",
            file=sys.stderr,
        )
        return 1
    except KeyboardInterrupt:
        print(
            "snowjax sweep: interrupted; run the same command again to resume",
            file=sys.stderr,
        )
        return 130
    r = result
    print(
        f"snowjax sweep: {r.n_points:,} points in {r.n_chunks} chunk(s) of {r.chunk_size}"
        f" ({r.computed_chunks} computed, {r.skipped_chunks} already on disk or another"
        f" process's) in {r.elapsed_s:.1f} s"
        + (f", {r.points_per_second:,.0f} points/s" if r.computed_chunks else "")
    )
    if r.complete:
        for path in [*r.files.values()] or [r.out]:
            print(f"  wrote {path}")
    else:
        print("  chunks of other processes are still missing; outputs not written yet")
    return 0
