"""Figure beyond the thesis for `snowjax reproduce`: the chapter-3 tyre forces on the
chapter-4 snow against the rigid-wheel lateral model, over slip x slip angle.
"""

from __future__ import annotations

import jax
import numpy as np

from .._coupled.tire_on_snow import tire_forces_on_snow
from .._terrain.wong import WongSnow
from .._tire.tire import lateral_friction
from .._wheel.equilibrium import Status, solve_wheel
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


INFLATION_KPA = (70.0, 350.0)  # the range of Fig. T.3 [kPa]
DEFLECTING_SLIP = 0.2  # [-]
SECTION_HEIGHT = 0.176  # [m], P235/75R15: 0.75 x 0.235 m

DEFLECTING_CAPTION = (
    "Beyond the thesis, whose wheel is a rigid rim. Sinkage, motion resistance and drawbar "
    "pull at slip 0.2 against inflation pressure p_i for the thesis tyre's size (0.736 m x "
    "0.235 m, section height 0.176 m, carcass pressure p_c = 0) as a deflecting tyre "
    "(`DeflectingTire`: Bekker's / Wong's rigid and elastic modes with a smooth switch) on "
    "the fresh snow of Table 4.1, at the thesis's loads 3.5, 5, 7.5 kN (colours); dashed: "
    "the rigid rim (the tyre at p_i = 1e12 Pa, the rim within the quadrature's 1e-7); "
    "dotted verticals: the mode boundary, where p_i + p_c equals the "
    "pressure the rigid rim puts on its lowest point (Wong's critical pressure p_gcr). "
    "The last panel: chapter 3's net longitudinal force on snow (`tire_forces_on_snow`, "
    "3.14 minus the motion resistance) with the tyre's and the rim's motion resistance."
)


@figure(
    "T.3",
    "deflecting tyre vs rigid rim over inflation pressure on the thesis snow",
    DEFLECTING_CAPTION,
    ("4.14", "4.15", "4.16", "2.10", "3.14"),
)
def fig_deflecting_tire(ctx: Context) -> FigureResult:
    from .._wheel.tire import DeflectingTire

    rim = RigidWheel.thesis_tire()
    snow = WongSnow.thesis_fresh_snow()
    p_kpa = np.linspace(*INFLATION_KPA, 8 if ctx.small else 57)
    loads = np.array(WHEEL_LOADS)[:, None]
    # The last column, p_i = 1e12 Pa, is the rigid rim (the tyre's limit, tested to
    # 1e-9): one solve and one chapter-3 evaluation for the tyres and the rim.
    pressures = np.append(p_kpa * 1e3, 1e12)[None, :]
    tires = DeflectingTire(rim.diameter, rim.width, SECTION_HEIGHT, pressures)
    both = solve_wheel(tires, snow, loads, DEFLECTING_SLIP)
    net_both = np.asarray(
        tire_forces_on_snow(tires, snow, loads, DEFLECTING_SLIP, 0.0).longitudinal_force
    )
    st = jax.tree.map(lambda x: x[:, :-1], both)
    rigid = jax.tree.map(lambda x: x[:, -1], both)
    net, net_rigid = net_both[:, :-1], net_both[:, -1]
    deflection = np.asarray(tires.deflection(both.entry_angle, snow))[:, :-1]
    # The mode boundary: the rigid rim's pressure on its lowest point (p_c = 0).
    p_gcr = np.asarray(snow.pressure(rigid.sinkage, rim.width)) / 1e3
    statuses = {int(s) for s in np.asarray(st.status).ravel()}
    statuses |= {int(s) for s in np.asarray(rigid.status).ravel()}

    panels = (
        ("sinkage [mm]", 1e3 * np.asarray(st.sinkage), 1e3 * np.asarray(rigid.sinkage)),
        ("motion resistance [N]", np.asarray(st.motion_resistance), rigid.motion_resistance),
        ("drawbar pull [N]", np.asarray(st.drawbar_pull), rigid.drawbar_pull),
        ("chapter 3 on snow: net F_x [N]", net, net_rigid),
    )
    # Only equilibria are drawn: at 7.5 kN and 70-80 kPa the undeflected circle would need
    # an entry angle beyond 85 degrees (Status.ENTRY_ANGLE_LIMIT).
    converged = np.asarray(st.status) == Status.CONVERGED
    fig, axes = subplots(1, len(panels), figsize=(15, 4.0))
    for ax, (label, values, rim_values) in zip(axes, panels):
        values = np.where(converged, values, np.nan)
        for a, load in enumerate(WHEEL_LOADS):
            ax.plot(p_kpa, values[a], "-", color=f"C{a}", label=f"tyre, F_z = {load / 1e3:g} kN")
            ax.axhline(float(np.asarray(rim_values)[a]), color=f"C{a}", ls="--", lw=0.8)
            ax.axvline(p_gcr[a], color=f"C{a}", ls=":", lw=0.8)
        ax.set_xlabel("inflation pressure p_i [kPa]")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle(
        "Fig. T.3 (beyond the thesis): deflecting tyre (solid) vs rigid rim (dashed), "
        "slip 0.2; dotted: mode boundary",
        fontsize=10,
    )
    fig.tight_layout()

    rows = [
        [
            float(load),
            float(p_kpa[k]),
            float(deflection[a, k]),
            float(np.asarray(st.sinkage)[a, k]),
            float(np.asarray(st.motion_resistance)[a, k]),
            float(np.asarray(st.drawbar_pull)[a, k]),
            float(net[a, k]),
            int(np.asarray(st.status)[a, k]),
        ]
        for a, load in enumerate(WHEEL_LOADS)
        for k in range(p_kpa.size)
    ]
    cols = [
        "load_N",
        "inflation_pressure_kPa",
        "deflection_m",
        "sinkage_m",
        "motion_resistance_N",
        "drawbar_pull_N",
        "net_Fx_chapter3_on_snow_N",
        "status",
    ]
    a5 = list(WHEEL_LOADS).index(5000.0)
    low = 0  # p_i = 70 kPa
    comparison = (
        "Not in the thesis. The rigid rim presses "
        + ", ".join(f"{p:.0f}" for p in p_gcr)
        + " kPa on its lowest point at 3.5, 5 and 7.5 kN (slip 0.2): a tyre inflated above "
        "that runs as the rim (sinkage, resistance and pull equal to it); below, it "
        f"flattens. At 5 kN and p_i = {p_kpa[low]:.0f} kPa the tyre deflects "
        f"{1e3 * deflection[a5, low]:.0f} mm and sinks {1e3 * float(st.sinkage[a5, low]):.0f} "
        f"mm against the rim's {1e3 * float(rigid.sinkage[a5]):.0f} mm; its motion "
        f"resistance is {float(st.motion_resistance[a5, low]):.0f} N against "
        f"{float(rigid.motion_resistance[a5]):.0f} N and its drawbar pull "
        f"{float(st.drawbar_pull[a5, low]):.0f} N against {float(rigid.drawbar_pull[a5]):.0f} "
        "N. Statuses: "
        + ", ".join(sorted(status_names(statuses)))
        + f" (ENTRY_ANGLE_LIMIT, not drawn: {int((~converged).sum())} point(s) at 7.5 kN "
        "and the lowest inflation pressures, where the undeflected circle would enter the "
        "snow beyond 85 degrees)."
    )
    ratio = float(st.motion_resistance[a5, low]) / float(rigid.motion_resistance[a5])
    return FigureResult(
        fig,
        cols,
        rows,
        comparison,
        verdict=f"at 5 kN a 70 kPa tyre has {ratio:.2f}x the rim's motion resistance",
    )
