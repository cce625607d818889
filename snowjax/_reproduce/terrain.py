"""Figure beyond the thesis for `snowjax reproduce`: the wheel on every terrain law.

Sinkage and drawbar pull against slip for the thesis tyre on Wong's snow (Table 4.1),
Bekker's Snow (U.S.) set (Wong's Table 2.3) and the layered snow of
`LayeredSnow.ice_layer_example`, each with the thesis's front-region distribution and
with the Wong–Reece (1967) distribution (c1 = 0.43, c2 = 0.32).
"""

from __future__ import annotations

import numpy as np

from .._terrain.bekker import BekkerSoil
from .._terrain.layered import LayeredSnow
from .._terrain.wong import WongSnow
from .._wheel.distribution import WongReece
from .._wheel.equilibrium import solve_wheel
from .._wheel.geometry import RigidWheel
from .._wheel.model import ContactModel
from .plotting import status_names, subplots
from .spec import Context, FigureResult, figure

TERRAIN_LOAD = 1000.0  # [N]: carried by all three terrains with both distributions

TERRAIN_CAPTION = (
    "Beyond the thesis (its future-work section asks for layered snow; the Wong–Reece "
    "distribution is what peer codes use). The 0.736 m × 0.235 m tyre at 1 kN on Wong's "
    "snow (Table 4.1 ratios, p_w = 85.55 kPa), on Bekker's Snow (U.S.) (n 1.6, k_c 4.37 "
    "kN/m^2.6, k_φ 196.72 kN/m^3.6, K 10 mm) and on a layered snow (ice at 10 cm breaking "
    "at 60 kPa over snow on frozen ground at 30 cm), classic shear, solid lines: the "
    "thesis's front-region distribution (0 ≤ θ ≤ θ0), dashed: Wong–Reece "
    "(θm = (0.43 + 0.32 i) θ0, θr = 0)."
)


@figure(
    "T.1",
    "terrain laws and stress distributions: sinkage and drawbar pull vs slip",
    TERRAIN_CAPTION,
    ("2.1", "2.3", "4.5", "4.10", "4.11", "4.14", "Wong–Reece 1967"),
)
def fig_terrains(ctx: Context) -> FigureResult:
    slips = np.linspace(-0.4, 0.9, 8 if ctx.small else 27)
    wheel = RigidWheel.thesis_tire()
    terrains = {
        "Wong snow (Table 4.1)": WongSnow.thesis_fresh_snow(),
        "Bekker Snow (U.S.)": BekkerSoil.snow_us(),
        "layered snow with ice": LayeredSnow.ice_layer_example(),
    }
    dists = {"front region": None, "Wong–Reece": WongReece(0.43, 0.32)}
    fig, (ax_z, ax_dp) = subplots(1, 2, figsize=(11, 4.2))
    rows, statuses, summary = [], set(), {}
    for (name, terrain), color in zip(terrains.items(), ("C0", "C1", "C2")):
        for (dname, dist), style in zip(dists.items(), ("-", "--")):
            st = solve_wheel(wheel, ContactModel(terrain, dist), TERRAIN_LOAD, slips)
            z = 100 * np.asarray(st.sinkage)
            dp = np.asarray(st.drawbar_pull)
            statuses |= set(int(s) for s in np.asarray(st.status))
            label = f"{name}, {dname}"
            ax_z.plot(slips, z, style, color=color, label=label)
            ax_dp.plot(slips, dp, style, color=color, label=label)
            summary[(name, dname)] = (z, dp)
            rows += [
                [name, dname, float(i), float(a), float(b), int(s)]
                for i, a, b, s in zip(slips, z, dp, np.asarray(st.status))
            ]
    ax_z.set(xlabel="slip i [-]", ylabel="sinkage z0 [cm]")
    ax_dp.set(xlabel="slip i [-]", ylabel="drawbar pull [N]")
    ax_dp.axhline(0, color="k", lw=0.6)
    ax_dp.legend(fontsize=7)
    ax_z.set_title("Fig. T.1 (beyond the thesis): sinkage vs slip", fontsize=10)
    ax_dp.set_title("Fig. T.1 (beyond the thesis): drawbar pull vs slip", fontsize=10)
    fig.tight_layout()

    k0 = int(np.argmin(np.abs(slips - 0.3)))
    parts, lower = [], 0
    for name in terrains:
        lower += int(np.sum(summary[(name, "Wong–Reece")][1] < summary[(name, "front region")][1]))
        zf, dpf = summary[(name, "front region")]
        zw, dpw = summary[(name, "Wong–Reece")]
        parts.append(
            f"{name}: sinkage {zf[k0]:.1f} cm (front) vs {zw[k0]:.1f} cm (Wong–Reece), "
            f"drawbar pull {dpf[k0]:.0f} N vs {dpw[k0]:.0f} N"
        )
    comparison = (
        f"Not in the thesis. At slip {slips[k0]:.2f}: " + "; ".join(parts) + ". The "
        "Wong–Reece distribution moves the stress peak forward of the axle and unloads the "
        "rear, so the same load needs a larger entry angle (more sinkage); the larger "
        "contact raises both the motion resistance and the thrust, and drawbar pull is "
        f"lower with Wong–Reece at {lower} of the {3 * len(slips)} (terrain, slip) points. "
        "Bekker's Snow (U.S.) is much softer under this narrow tyre than the "
        "thesis's snow. On the layered snow the ice carries the wheel until it breaks under "
        "the rim; the equilibrium is the shallowest one. Statuses: "
        + ", ".join(sorted(status_names(statuses)))
        + "."
    )
    cols = ["terrain", "distribution", "slip", "sinkage_cm", "drawbar_pull_N", "status"]
    return FigureResult(
        fig,
        cols,
        rows,
        comparison,
        verdict=f"Wong–Reece: more sinkage; lower drawbar pull at {lower} of "
        f"{3 * len(slips)} points",
    )
