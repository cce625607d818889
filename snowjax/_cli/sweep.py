"""`snowjax sweep`: chunked, resumable, sharded sweeps of the wheel equilibrium to disk.

    snowjax sweep --loads 2000:8000:13 --slips 0:0.9:10 --p-w 60e3,85.55e3 --out DIR

    snowjax sweep --terrain bekker --preset snow-us --k-phi 150e3,200e3 \
        --distribution wong-reece --c1 0.43 --c2 0.32 --loads 300:900:4 --out DIR

Value lists are `start:stop:num` (like `numpy.linspace`), a comma list, or one value.
By default the sweep is the grid parameter sets x loads x slips; parameter options
given as lists are zipped into parameter sets (equal lengths, or one value), or
combined into every combination with `--param-grid`.  `--list` zips loads, slips and
parameter lists instead of the grid (one point each).  Options that would do nothing are
refused: `--param-grid` with `--list` or without a parameter list, `--coordinator`,
`--num-processes` and `--process-id` without `--distributed`.

Terrains (`--terrain`, SI units):
  wong     WongSnow: --p-w [Pa] --z-w [m] --cohesion [Pa] --tan-phi [-]
           --shear-modulus [m]; presets (--preset or --snow) thesis (default),
           plate-rule: the thesis's Table 4.1 ratios for D = 0.736 m; when only
           --p-w is given the cohesion follows c = 0.2165 p_w.
  bekker   BekkerSoil: --n [-] --k-c [N/m^(n+1)] --k-phi [N/m^(n+2)] --cohesion
           --tan-phi --shear-modulus; presets snow-us (default), snow-harrison,
           snow-sweden (Wong, Table 2.3), thesis-lab-snow.
  reece    ReeceSoil: --n --k-c-prime [-] --k-phi-prime [-] --unit-weight [N/m^3]
           --cohesion --tan-phi (all required: no preset) --shear-modulus (default
           10 mm).
  layered  LayeredSnow: preset ice-layer-example (default); its leaves are set with
           --set top.p_w=30e3 --set bottom.z_w=0.3 --set ice_failure_pressure=60e3.
`--set NAME=VALUES` sets any terrain leaf by its column name (repeatable).
Stress distribution: `--distribution none` (default, the thesis's front region) or
`wong-reece` with --c1, --c2, --c3 [-] (defaults 0.43, 0.32, 0; lists allowed).

Running the same command again resumes an interrupted sweep; a different sweep (also
another terrain or distribution) in the same `--out` is refused (use `--restart` to
discard it).  See `snowjax.sweep`.
"""

from __future__ import annotations

import argparse
import itertools
import pathlib
import sys

_PARAMETERS = (
    # (option, field, object); the unit comes from the field's ParameterInfo
    ("p-w", "p_w", "snow"),
    ("z-w", "z_w", "snow"),
    ("cohesion", "cohesion", "snow"),
    ("tan-phi", "tan_phi", "snow"),
    ("shear-modulus", "shear_modulus", "snow"),
    ("diameter", "diameter", "wheel"),
    ("width", "width", "wheel"),
    ("n", "n", "terrain"),
    ("k-c", "k_c", "terrain"),
    ("k-phi", "k_phi", "terrain"),
    ("k-c-prime", "k_c_prime", "terrain"),
    ("k-phi-prime", "k_phi_prime", "terrain"),
    ("unit-weight", "unit_weight", "terrain"),
    ("c1", "c1", "distribution"),
    ("c2", "c2", "distribution"),
    ("c3", "c3", "distribution"),
)
_TERRAINS = ("wong", "bekker", "reece", "layered")
_PRESETS = {
    "wong": ("thesis", "plate-rule"),
    "bekker": ("snow-us", "snow-harrison", "snow-sweden", "thesis-lab-snow"),
    "reece": (),
    "layered": ("ice-layer-example",),
}
_REECE_REQUIRED = ("n", "k_c_prime", "k_phi_prime", "unit_weight", "cohesion", "tan_phi")


def _units() -> dict[str, str]:
    """Field name -> unit, from the `ParameterInfo` of the fields of the built-in classes."""
    from .._leaves import _own_parameter_fields
    from .._terrain.bekker import BekkerSoil
    from .._terrain.reece import ReeceSoil
    from .._terrain.wong import WongSnow
    from .._wheel.distribution import WongReece
    from .._wheel.geometry import RigidWheel

    return {
        name: info.unit
        for cls in (RigidWheel, WongSnow, BekkerSoil, ReeceSoil, WongReece)
        for name, info in _own_parameter_fields(cls)
        if info is not None
    }


def register(sub) -> None:
    p = sub.add_parser(
        "sweep",
        help="chunked, resumable sweeps of the wheel equilibrium to disk",
        description=(__doc__ or "").split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _model_arguments(p)
    _run_arguments(p)
    _distributed_arguments(p)
    p.set_defaults(run=run)


def _model_arguments(p) -> None:
    """The points and the model: loads, slips, shear law, terrain and its parameters,
    stress distribution."""
    p.add_argument("--loads", default="2000:8000:13", help="wheel loads [N] (default %(default)s)")
    p.add_argument("--slips", default="0:0.9:10", help="driving slips [-] (default %(default)s)")
    p.add_argument("--shear", choices=("classic", "simplified", "none"), default="classic")
    p.add_argument(
        "--terrain",
        choices=_TERRAINS,
        default="wong",
        help="terrain law: WongSnow, BekkerSoil, ReeceSoil or LayeredSnow (default %(default)s)",
    )
    p.add_argument(
        "--preset",
        default=None,
        help="preset parameter set of the terrain: wong: thesis (default), plate-rule;"
        " bekker: snow-us (default), snow-harrison, snow-sweden, thesis-lab-snow;"
        " layered: ice-layer-example (default); reece: none",
    )
    p.add_argument(
        "--snow",
        choices=("thesis", "plate-rule"),
        default=None,
        help="(--terrain wong) preset snow: the thesis's fresh snow (p_w 85.55 kPa) or its"
        " plate-rule variant (p_w 12.92 kPa), Table 4.1 ratios for D = 0.736 m (default"
        " thesis)",
    )
    units = _units()
    for option, field, obj in _PARAMETERS:
        p.add_argument(
            f"--{option}",
            default=None,
            metavar="VALUES",
            help=f"override {obj} {field} [{units[field]}]; a list gives several parameter sets",
        )
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUES",
        help="set any terrain leaf by its column name, e.g. top.p_w=30e3 (repeatable)",
    )
    p.add_argument(
        "--distribution",
        choices=("none", "wong-reece"),
        default="none",
        help="stress distribution: the thesis's front region or Wong-Reece (1967) with"
        " --c1, --c2, --c3 (default %(default)s)",
    )


def _run_arguments(p) -> None:
    """The sweep's layout and the solver's settings: grid or list, output, chunks,
    formats, nodes, steps, dtype, workers, progress."""
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
    p.add_argument(
        "--chunk-size", type=int, default=8192, help="rows per chunk (default %(default)s)"
    )
    p.add_argument(
        "--format",
        default="npz,csv",
        help="consolidated outputs: npz, csv, both or none"
        " (the chunk files are always kept) (default %(default)s)",
    )
    p.add_argument("--nodes-per-panel", type=int, default=None, help="quadrature nodes per panel")
    p.add_argument(
        "--accuracy",
        choices=("reference", "simulator"),  # ContactModel's ACCURACIES (no jax import here)
        default="reference",
        help="quadrature: reference (1e-7) or simulator (fewer nodes; up to 3e-4 of the load)",
    )
    p.add_argument("--max-steps", type=int, default=64, help="Newton iteration limit")
    p.add_argument("--float32", action="store_true", help="solve in float32 (default float64)")
    p.add_argument("--restart", action="store_true", help="discard a sweep already in --out")
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        help="processes sharing the chunks, each pinned to its own CPU core (default: one"
        " per core from 1,000,000 points on, else 1)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def _distributed_arguments(p) -> None:
    """A multi-host sweep (`jax.distributed.initialize`)."""
    p.add_argument(
        "--distributed",
        action="store_true",
        help="call jax.distributed.initialize() first (multi-host; chunk k is computed by"
        " process k %% process_count)",
    )
    p.add_argument("--coordinator", default=None, help="with --distributed: host:port of process 0")
    p.add_argument("--num-processes", type=int, default=None, help="with --distributed")
    p.add_argument("--process-id", type=int, default=None, help="with --distributed")
    p.add_argument(
        "--heartbeat-timeout",
        type=int,
        default=None,
        metavar="SECONDS",
        help="with --distributed: a process that sends no heartbeat for this long is taken"
        " as dead and the run is stopped (default: JAX's, 100 s)",
    )


# At most this many values per list: 10^8 float64 values are 0.75 GiB before any solving.
MAX_VALUES = 10**8


def _gib(n_bytes: float) -> str:
    return f"{n_bytes / 2**30:,.1f} GiB"


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
            if int(num) > MAX_VALUES:
                raise OverflowError(int(num))
            return np.linspace(start, stop, int(num))
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise ValueError(
            f"--{option} {text!r}: expected start:stop:num (num a positive integer), a comma"
            " list of numbers, or one number"
        ) from None
    except OverflowError as err:
        n = err.args[0]
        raise ValueError(
            f"--{option} {text!r}: {n:,} values would take {_gib(8 * n)} before solving;"
            f" at most {MAX_VALUES:,} per list"
        ) from None
    return np.asarray(values)


def _check_output_size(out: str, n_points: int, formats) -> None:
    """Refuse a sweep whose files cannot fit on the disk that holds `out`."""
    import shutil

    # Per row: chunk files plus each consolidated output, ~16 float64 columns each (npz)
    # or ~16 columns of ~20 characters (csv).
    per_row = 16 * 8 + sum(16 * (8 if f == "npz" else 20) for f in formats)
    need = n_points * per_row
    where = pathlib.Path(out).resolve()
    while not where.exists():
        where = where.parent
    free = shutil.disk_usage(where).free
    if need > free:
        raise ValueError(
            f"{n_points:,} points would write about {_gib(need)} of files; {_gib(free)} free"
            f" at {where}"
        )


def _build(args):
    """The sweep's inputs from the options: (wheel, terrain, distribution, loads, slips,
    formats)."""
    import numpy as np

    from .._wheel.distribution import WongReece
    from .._wheel.geometry import RigidWheel

    loads = _values(args.loads, "loads")
    slips = _values(args.slips, "slips")
    # Every parameter option given: key -> (object, field path, values, option text).
    given = {}
    for option, field, obj in _PARAMETERS:
        text = getattr(args, option.replace("-", "_"))
        if text is not None:
            given[option] = (obj, field, _values(text, option), f"--{option}")
    for item in args.set:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise ValueError(f"--set {item!r}: expected NAME=VALUES, e.g. top.p_w=30e3")
        if f"set:{name}" in given or any(f == name for _, f, *_ in given.values()):
            raise ValueError(f"--set {item!r}: {name} is given twice")
        given[f"set:{name}"] = ("terrain", name, _values(text, "set " + name), f"--set {name}")
    multi = [k for k, v in given.items() if v[2].size > 1]
    if args.param_grid and not multi:
        raise ValueError(
            "--param-grid combines parameter lists, but no parameter option has more than one value"
        )
    if args.param_grid and not args.list:
        # Every combination of the parameter lists (first option slowest).
        combos = np.array(list(itertools.product(*(given[k][2] for k in multi))))
        for j, k in enumerate(multi):
            given[k] = (*given[k][:2], combos[:, j], given[k][3])
    elif not args.list and len({given[k][2].size for k in multi}) > 1:
        sizes = ", ".join(f"{given[k][3]} has {given[k][2].size}" for k in multi)
        raise ValueError(
            f"parameter lists are zipped into parameter sets and must have the same length"
            f" (or one value): {sizes}; use --param-grid for every combination"
        )
    values = {}  # (object, field) -> scalar or array
    for obj, field, x, _ in given.values():
        values[("terrain" if obj == "snow" else obj, field)] = x[0] if x.size == 1 else x
    options = {(("terrain" if obj == "snow" else obj), field): opt
               for obj, field, _, opt in given.values()}  # fmt: skip
    value = lambda obj, f, default: values.get((obj, f), default)  # noqa: E731

    terrain_given = {f: v for (obj, f), v in values.items() if obj == "terrain"}
    snow = terrain_from_options(args.terrain, args.preset, args.snow, terrain_given, options)
    dist_given = {f: v for (obj, f), v in values.items() if obj == "distribution"}
    if args.distribution == "wong-reece":
        ref = WongReece.reference()
        distribution = WongReece(
            c1=value("distribution", "c1", ref.c1),
            c2=value("distribution", "c2", ref.c2),
            c3=value("distribution", "c3", ref.c3),
        )
    else:
        if dist_given:
            raise ValueError(
                ", ".join(options[("distribution", f)] for f in dist_given)
                + " only apply with --distribution wong-reece"
            )
        distribution = None
    thesis = RigidWheel.thesis_tire()
    wheel = RigidWheel(
        diameter=value("wheel", "diameter", thesis.diameter),
        width=value("wheel", "width", thesis.width),
    )
    formats = tuple(f.strip() for f in args.format.split(",") if f.strip() and f.strip() != "none")
    for f in formats:
        if f not in ("npz", "csv"):
            raise ValueError(f"--format {args.format!r}: choose from npz, csv, none")
    return wheel, snow, distribution, loads, slips, formats


def terrain_from_options(terrain_kind, preset_name, snow_preset, terrain_given, options):
    """The terrain of `--terrain`, `--preset` / `--snow` and the parameter options.

    - `terrain_kind`: "wong", "bekker", "reece" or "layered".
    - `preset_name`: `--preset` (or None for the default preset); `snow_preset`:
      `--snow` (WongSnow only, or None).
    - `terrain_given`: field path -> value (scalar or 1-D array, SI units).
    - `options`: ("terrain", field path) -> option text, for the error messages.

    Raises `ValueError` naming the option for a parameter the terrain does not have, an
    unknown preset or missing parameters.
    """
    import numpy as np

    from .._constants import PLATE_RULE_P_W, THESIS_P_W
    from .._leaves import _module_leaves, _with_leaves
    from .._terrain.bekker import BekkerSoil
    from .._terrain.layered import LayeredSnow
    from .._terrain.reece import ReeceSoil
    from .._terrain.wong import WongSnow

    value = lambda f, default: terrain_given.get(f, default)  # noqa: E731
    if snow_preset is not None:
        if terrain_kind != "wong":
            raise ValueError(
                f"--snow is a WongSnow preset; use --preset with --terrain {terrain_kind}"
            )
        if preset_name is not None and preset_name != snow_preset:
            raise ValueError(f"--snow {snow_preset} and --preset {preset_name} disagree")
        preset_name = snow_preset
    if preset_name is not None and preset_name not in _PRESETS[terrain_kind]:
        choices = ", ".join(_PRESETS[terrain_kind]) or "none (give every parameter)"
        raise ValueError(
            f"--preset {preset_name!r} is not a preset of --terrain {terrain_kind}; choose"
            f" from: {choices}"
        )
    if terrain_kind == "wong":
        # The presets are the thesis's Table 4.1 ratios for D = 0.736 m; the cohesion
        # follows c = 0.2165 p_w when only p_w is overridden.
        preset_p_w = THESIS_P_W if preset_name in (None, "thesis") else PLATE_RULE_P_W
        preset = WongSnow.thesis_fresh_snow(p_w=value("p_w", preset_p_w))
        _only(terrain_given, WongSnow, options, terrain_kind)
        snow = WongSnow(
            p_w=preset.p_w,
            z_w=value("z_w", preset.z_w),
            cohesion=value("cohesion", preset.cohesion),
            tan_phi=value("tan_phi", preset.tan_phi),
            shear_modulus=value("shear_modulus", preset.shear_modulus),
        )
    else:
        if terrain_kind == "reece":
            missing = [f for f in _REECE_REQUIRED if f not in terrain_given]
            if missing:
                raise ValueError(
                    "--terrain reece has no preset: give "
                    + ", ".join("--" + f.replace("_", "-") for f in missing)
                )
            base = ReeceSoil(**{f: 1.0 for f in _REECE_REQUIRED})
        elif terrain_kind == "bekker":
            base = {
                "snow-us": BekkerSoil.snow_us, "snow-harrison": BekkerSoil.snow_harrison,
                "snow-sweden": BekkerSoil.snow_sweden,
                "thesis-lab-snow": BekkerSoil.thesis_lab_snow,
            }[preset_name or "snow-us"]()  # fmt: skip
        else:
            base = LayeredSnow.ice_layer_example()
        _only(terrain_given, type(base), options, terrain_kind, _module_leaves(base))
        snow = _with_leaves(base, {f: np.asarray(v, float) for f, v in terrain_given.items()})
    return snow


def _only(given, cls, options, kind, leaves=None):
    """Refuse parameter options that are not leaves of the chosen terrain."""
    import dataclasses

    names = list(leaves) if leaves is not None else [f.name for f in dataclasses.fields(cls)]
    wrong = [f for f in given if f not in names]
    if wrong:
        raise ValueError(
            ", ".join(options[("terrain", f)] for f in wrong)
            + f" is not a parameter of --terrain {kind} ({cls.__name__}: "
            + ", ".join(names)
            + ")"
        )


def _unused_options(args) -> None:
    """Refuse options that would do nothing in this combination (ValueError naming them)."""
    if args.list and args.param_grid:
        raise ValueError(
            "--param-grid does nothing with --list (--list zips loads, slips and parameter"
            " lists point by point); use one of them"
        )
    cluster = [f"--{o}" for o, v in (("coordinator", args.coordinator),
               ("num-processes", args.num_processes), ("process-id", args.process_id),
               ("heartbeat-timeout", args.heartbeat_timeout))
               if v is not None]  # fmt: skip
    if cluster and not args.distributed:
        verb = "applies" if len(cluster) == 1 else "apply"
        raise ValueError(f"{', '.join(cluster)} only {verb} with --distributed")
    if args.workers is not None and args.distributed:
        raise ValueError(
            "--workers does not apply with --distributed (its processes share the chunks)"
        )


# Set in the environment of the child process that `_supervised` runs a distributed
# sweep in.
SUPERVISED = "SNOWJAX_SWEEP_SUPERVISED"


def _supervised(args) -> int:
    """Run this process's part of a distributed sweep in a child process; report how it
    ended in one line.

    JAX's distributed service stops every process of a run when one of them dies or stops
    answering (no heartbeat for `--heartbeat-timeout` seconds, also at the shutdown
    barrier after the last chunk): it aborts them (SIGABRT) with a C++ stack trace.  The
    child's stderr goes to `OUT/.sweep.process<k>.log`; its own one-line messages are
    passed on, a crash becomes one line saying what happened and how to resume.
    """
    import os
    import signal
    import subprocess

    out = pathlib.Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        print(f"snowjax sweep: error: --out {out}: {err.strerror or err}", file=sys.stderr)
        return 2
    who = "this process" if args.process_id is None else f"process {args.process_id}"
    log = out / f".sweep.process{'' if args.process_id is None else args.process_id}.log"
    main = "import sys; from snowjax._cli.app import main; sys.exit(main())"
    command = [sys.executable, "-c", main, *args.argv]
    with log.open("w", encoding="utf-8") as err:
        child = subprocess.Popen(command, stderr=err, env={**os.environ, SUPERVISED: "1"})
        # A SIGTERM to this process stops the child too (SIGINT reaches both already).
        signal.signal(signal.SIGTERM, lambda *_: child.terminate())
        try:
            status = child.wait()
        except KeyboardInterrupt:  # the child got the same SIGINT: let it save and stop
            status = child.wait()
    text = log.read_text(encoding="utf-8", errors="replace")
    own = [line for line in text.splitlines() if line.startswith("snowjax sweep:")]
    if status >= 0 and own:
        print("\n".join(own), file=sys.stderr)
        return status
    if status == 0:
        return 0
    if "distributed service detected fatal errors" in text or "heartbeat" in text:
        why = (
            "JAX's distributed service stopped it because another process of the run died"
            " or stopped answering"
        )
    elif status < 0:
        why = f"it was stopped by {signal.Signals(-status).name}"
    else:
        why = f"it failed with exit status {status}"
    print(
        f"snowjax sweep: error: {who} of the distributed sweep ended: {why}; the chunks"
        f" written so far are kept in {out}: run the same command again on every process"
        f" to resume (log: {log})",
        file=sys.stderr,
    )
    return 1


def run(args) -> int:
    try:
        _unused_options(args)
        if args.chunk_size < 1:
            raise ValueError(f"--chunk-size must be a positive integer, got {args.chunk_size}")
        if not args.out.strip():
            raise ValueError("--out must name a directory, got ''")
        if args.heartbeat_timeout is not None and args.heartbeat_timeout < 1:
            raise ValueError(f"--heartbeat-timeout must be >= 1 s, got {args.heartbeat_timeout}")
    except ValueError as err:
        print(f"snowjax sweep: error: {err}", file=sys.stderr)
        return 2
    import os

    if args.distributed and os.environ.get(SUPERVISED) != "1":
        return _supervised(args)
    try:
        import jax
        import numpy as np

        jax.config.update("jax_enable_x64", not args.float32)
        if args.distributed:
            heartbeat = {}
            if args.heartbeat_timeout is not None:
                heartbeat["heartbeat_timeout_seconds"] = args.heartbeat_timeout
            jax.distributed.initialize(
                coordinator_address=args.coordinator,
                num_processes=args.num_processes,
                process_id=args.process_id,
                **heartbeat,
            )
        from .._sweep.sweep import SweepRun, rate_text, sweep
        from .._wheel.model import ContactModel

        wheel, snow, distribution, loads, slips, formats = _build(args)
        n_sets = max([1, *(np.size(x) for x in jax.tree_util.tree_leaves((wheel, snow)))])
        n_points = len(loads) if args.list else len(loads) * len(slips) * n_sets
        _check_output_size(args.out, n_points, formats)
        model = ContactModel(
            snow,
            distribution,
            args.shear,
            nodes_per_panel=args.nodes_per_panel,
            accuracy=args.accuracy,
        )
        result = sweep(
            wheel,
            model,
            loads,
            slips,
            out=args.out,
            grid=not args.list,
            formats=formats,
            progress=not args.no_progress,
            max_steps=args.max_steps,
            run=SweepRun(args.chunk_size, resume=not args.restart, workers=args.workers),
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
    except RuntimeError as err:  # a worker process failed; its chunks so far are kept
        message = str(err).removeprefix("sweep: ")
        print(f"snowjax sweep: error: {message}", file=sys.stderr)
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
        + (f", {rate_text(r.points_per_second)} points/s" if r.computed_chunks else "")
    )
    if r.complete:
        for path in [*r.files.values()] or [r.out]:
            print(f"  wrote {path}")
    else:
        print("  chunks of other processes are still missing; outputs not written yet")
    return 0
