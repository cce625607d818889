"""`snowjax reproduce`: the main job.

`snowjax reproduce [--out DIR]` sweeps the thesis's rigid wheel (0.736 m x 0.235 m) on its
fresh shallow snow (Table 4.1) over slips and loads with the three shear models, prints a
table, and writes the numbers (CSV) and the sinkage / motion-resistance-vs-slip figures
(thesis Fig. 4.7 and 4.8) to DIR.
"""

from __future__ import annotations

import argparse
import csv
import pathlib
import sys
import time


def _reproduce(out: pathlib.Path, n_slips: int) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from rich.console import Console
    from rich.progress import Progress
    from rich.table import Table

    import snowjax as sj

    console = Console()
    out.mkdir(parents=True, exist_ok=True)
    wheel = sj.RigidWheel.thesis_tire()
    snow = sj.WongSnow.thesis_fresh_snow()
    loads = np.array([3500.0, 5000.0, 7500.0])
    slips = np.linspace(0.0, 0.95, n_slips)
    shears = ("classic", "simplified", "none")
    results = {}
    start = time.perf_counter()
    with Progress(console=console, transient=True) as progress:
        task = progress.add_task("Solving eq. (4.14) for each shear model", total=len(shears))
        for shear in shears:
            results[shear] = sj.solve_wheel(wheel, snow, loads[:, None], slips[None, :], shear)
            progress.advance(task)
    elapsed = time.perf_counter() - start

    rows = []
    for shear, st in results.items():
        for i, load in enumerate(loads):
            for k, slip in enumerate(slips):
                rows.append(dict(
                    shear=shear, load_N=load, slip=slip,
                    entry_angle_deg=float(np.degrees(st.entry_angle[i, k])),
                    sinkage_m=float(st.sinkage[i, k]),
                    motion_resistance_N=float(st.motion_resistance[i, k]),
                    thrust_N=float(st.thrust[i, k]),
                    drawbar_pull_N=float(st.drawbar_pull[i, k]),
                    torque_Nm=float(st.torque[i, k]),
                    status=sj.Status(int(st.status[i, k])).name,
                ))
    with open(out / "wheel_sweep.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)

    table = Table(title="Thesis tyre on fresh shallow snow, F_z = 5 kN (eq. 4.14-4.16)")
    for col in ("slip", "model", "sinkage [cm]", "motion res. [N]", "drawbar pull [N]", "torque [N m]", "status"):
        table.add_column(col, justify="right")
    for k in range(0, n_slips, max(1, n_slips // 5)):
        for shear in shears:
            st = results[shear]
            table.add_row(
                f"{slips[k]:.2f}", shear, f"{100 * float(st.sinkage[1, k]):.2f}",
                f"{float(st.motion_resistance[1, k]):.1f}", f"{float(st.drawbar_pull[1, k]):.1f}",
                f"{float(st.torque[1, k]):.1f}", sj.Status(int(st.status[1, k])).name,
            )
    console.print(table)

    styles = {"classic": "-", "simplified": "--", "none": ":"}
    for field, ylabel, fig_no, scale in (
        ("sinkage", "sinkage z0 [cm]", "4.7", 100.0),
        ("motion_resistance", "motion resistance R_x [N]", "4.8", 1.0),
    ):
        fig, ax = plt.subplots(figsize=(6.4, 4.4))
        for i, load in enumerate(loads):
            for shear in shears:
                ax.plot(slips, scale * np.asarray(getattr(results[shear], field))[i], styles[shear],
                        color=f"C{i}", label=f"{load / 1e3:.1f} kN, {shear}")
        ax.set_xlabel("slip i [-]")
        ax.set_ylabel(ylabel)
        ax.set_title(f"cf. thesis Fig. {fig_no}: {field.replace('_', ' ')} vs slip")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=3)
        fig.tight_layout()
        fig.savefig(out / f"fig_{fig_no.replace('.', '_')}_{field}_vs_slip.png", dpi=120)
        plt.close(fig)
    console.print(f"{len(rows)} equilibria in {elapsed:.1f} s (including JIT compilation); "
                  f"wrote {out}/wheel_sweep.csv and figures.")
    return 0


def register(sub) -> None:
    """Add the `reproduce` subcommand to the `snowjax` argument parser."""
    rep = sub.add_parser("reproduce", help="sweep the thesis wheel over slip and load; table, CSV, figures")
    rep.add_argument("--out", type=pathlib.Path, default=pathlib.Path("snowjax-output"),
                     help="output directory (default: ./snowjax-output)")
    rep.add_argument("--slips", type=int, default=20, help="number of slip values in [0, 0.95]")
    rep.set_defaults(run=run, parser=rep)


def run(args) -> int:
    if args.slips < 2:
        args.parser.error("--slips must be at least 2")
    return _reproduce(args.out, args.slips)
