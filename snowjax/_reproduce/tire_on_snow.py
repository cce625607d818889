"""Figure beyond the thesis for `snowjax reproduce`: the chapter-3 tyre forces on the
chapter-4 snow against the rigid-wheel lateral model, over slip x slip angle.
"""

from __future__ import annotations

import numpy as np

from .._coupled.tire_on_snow import tire_forces_on_snow
from .._terrain.wong import WongSnow
from .._tire.tire import lateral_friction
from .._wheel.equilibrium import solve_wheel
from .._wheel.geometry import RigidWheel
from .chapter4 import WHEEL_LOADS
from .plotting import status_names, subplots
from .spec import Context, FigureResult, figure

ON_SNOW_SLIPS = (0.05, 0.2, 0.5)  # [-]
MAX_SLIP_ANGLE_DEG = 30.0

ON_SNOW_CAPTION = (
    "Beyond the thesis, which never combines its chapters. Lateral force against slip "
    "angle 0–30° at the thesis's loads 3.5, 5, 7.5 kN (panels) and driving slips 0.05, "
    "0.2, 0.5 (colours), for the 0.736 m × 0.235 m tyre on the fresh snow of Table 4.1 "
    "(p_w = 85.55 kPa). Solid: chapter 3 on snow (`tire_forces_on_snow`: the combined "
    "lateral force (3.15) with the load functions (3.17)–(3.21); sinkage and motion "
    "resistance from the straight-running equilibrium 4.14–4.16). Dashed: the rigid wheel "
    "under a slip angle (`solve_wheel(..., slip_angle=...)`, classic shear: resultant "
    "Janosi–Hanamoto of the rim and axle shear displacements, K_y = K, no sidewall "
    "bulldozing)."
)


@figure(
    "T.2",
    "tyre on snow: chapter-3 combined lateral force vs rigid-wheel lateral model",
    ON_SNOW_CAPTION,
    ("3.7", "3.8", "3.9", "3.10", "3.15", "3.17", "3.18", "3.20", "3.21", "4.14", "4.16"),
)
def fig_tire_on_snow(ctx: Context) -> FigureResult:
    wheel = RigidWheel.thesis_tire()
    snow = WongSnow.thesis_fresh_snow()
    loads = np.array(WHEEL_LOADS)[:, None, None]
    slips = np.array(ON_SNOW_SLIPS)[None, :, None]
    angles_deg = np.linspace(0.0, MAX_SLIP_ANGLE_DEG, 7 if ctx.small else 31)
    angles = np.radians(angles_deg)[None, None, :]
    tyre = tire_forces_on_snow(wheel, snow, loads, slips, angles)
    rigid = solve_wheel(wheel, snow, loads, slips, slip_angle=angles)
    fy3 = np.asarray(tyre.lateral_force)
    fyr = np.asarray(rigid.lateral_force)
    fx3 = np.asarray(tyre.longitudinal_force)
    dpr = np.asarray(rigid.drawbar_pull)
    statuses = {int(s) for s in np.asarray(tyre.status).ravel()}
    statuses |= {int(s) for s in np.asarray(rigid.status).ravel()}

    fig, axes = subplots(1, len(WHEEL_LOADS), figsize=(13, 4.2))
    for a, (ax, load) in enumerate(zip(axes, WHEEL_LOADS)):
        for k, slip in enumerate(ON_SNOW_SLIPS):
            ax.plot(
                angles_deg, fy3[a, k], "-", color=f"C{k}", label=f"chapter 3 on snow, i = {slip:g}"
            )
            ax.plot(angles_deg, fyr[a, k], "--", color=f"C{k}", label=f"rigid wheel, i = {slip:g}")
        ax.set_title(f"F_z = {load / 1e3:g} kN", fontsize=9)
        ax.set_xlabel("slip angle α [deg]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("lateral force F_y [N]")
    axes[0].legend(fontsize=7)
    fig.suptitle(
        "Fig. T.2 (beyond the thesis): chapter-3 combined lateral force on snow vs "
        "rigid-wheel lateral model",
        fontsize=10,
    )
    fig.tight_layout()

    rows = [
        [
            float(load),
            float(slip),
            float(angles_deg[m]),
            float(fy3[a, k, m]),
            float(fyr[a, k, m]),
            float(fx3[a, k, m]),
            float(dpr[a, k, m]),
            float(np.asarray(tyre.sinkage)[a, k, m]),
            float(np.asarray(rigid.sinkage)[a, k, m]),
        ]
        for a, load in enumerate(WHEEL_LOADS)
        for k, slip in enumerate(ON_SNOW_SLIPS)
        for m in range(len(angles_deg))
    ]
    cols = [
        "load_N",
        "slip",
        "slip_angle_deg",
        "Fy_chapter3_on_snow_N",
        "Fy_rigid_wheel_N",
        "Fx_net_chapter3_on_snow_N",
        "drawbar_pull_rigid_wheel_N",
        "sinkage_chapter3_on_snow_m",
        "sinkage_rigid_wheel_m",
    ]
    # Numbers for the comparison: 5 kN, slip 0.2, at 10 deg (nearest) and 30 deg.
    a5, k2 = list(WHEEL_LOADS).index(5000.0), list(ON_SNOW_SLIPS).index(0.2)
    m10 = int(np.argmin(np.abs(angles_deg - 10.0)))
    ratio = fyr[..., 1:] / fy3[..., 1:]
    limit = np.array(WHEEL_LOADS) * np.asarray(lateral_friction(np.array(WHEEL_LOADS)))  # μ_y F_z
    comparison = (
        "Not in the thesis. At 5 kN and slip 0.2 the chapter-3 lateral force is "
        f"{fy3[a5, k2, m10]:.0f} N at α = {angles_deg[m10]:g}° and {fy3[a5, k2, -1]:.0f} N "
        f"at 30°; the rigid wheel gives {fyr[a5, k2, m10]:.0f} N and {fyr[a5, k2, -1]:.0f} N. "
        f"Over all loads, slips and α > 0 the rigid-wheel force is {ratio.min():.2f}–"
        f"{ratio.max():.2f} times the chapter-3 force. Chapter 3 saturates at μ_y F_z "
        f"({limit[0]:.0f} N at 3.5 kN, {limit[-1]:.0f} N at 7.5 kN: μ_y of (3.20) falls as "
        "the load rises) with the FEA-fitted lateral stiffness C_α (3.18) at small α; the "
        "rigid wheel's lateral shear is capped by Mohr–Coulomb over the whole contact "
        "(the cohesion c = 18.5 kPa dominates on this snow) and has not saturated by 30°. "
        "In both models the lateral force falls with slip, as the longitudinal slip takes "
        "up shear capacity (the combined slip (3.9); the resultant displacement of the "
        "rigid-wheel law), and both vanish at α = 0. "
        "The net longitudinal force of chapter 3 on snow (3.14 minus the motion resistance "
        f"4.16) at 5 kN, slip 0.2, α = 0 is {fx3[a5, k2, 0]:.0f} N, against the rigid "
        f"wheel's drawbar pull {dpr[a5, k2, 0]:.0f} N. Statuses: "
        + ", ".join(sorted(status_names(statuses)))
        + "."
    )
    return FigureResult(
        fig,
        cols,
        rows,
        comparison,
        verdict=f"rigid-wheel F_y is {ratio.min():.2f}–{ratio.max():.2f}× the chapter-3 F_y",
    )
