"""Figure beyond the thesis for `snowjax reproduce`: wheels in one track on the thesis
snow, each on the rut the earlier ones left (`snowjax.multi_pass`).
"""

from __future__ import annotations

import numpy as np

from .._terrain.wong import WongSnow
from .._wheel.geometry import RigidWheel
from .._wheel.passes import multi_pass
from .plotting import status_names, subplots
from .spec import Context, FigureResult, figure

PASSES = 6
# Unloading modulus k_u = k_0 + A_u z_u (Gawwad & Crolla, thesis eq. 2.21): illustrative,
# no measured values for snow in the sources cited.
K_0, A_U = 1e6, 5e6  # [Pa/m], [Pa/m^2]
SLIP = 0.2
SERIES = (
    ("equal loads, 5 kN", np.full(PASSES, 5000.0)),
    ("front 4 kN / heavier rear 6 kN", np.tile([4000.0, 6000.0], PASSES // 2)),
)

RUT_CAPTION = (
    "Beyond the thesis. Six wheels in one track on the fresh snow of Table 4.1 (p_w = "
    "85.55 kPa), the 0.736 m × 0.235 m wheel of chapter 4 (front region, classic shear, "
    "slip 0.2): equal 5 kN loads, and 4 kN / 6 kN alternating (the axles of vehicles with "
    "a heavier rear axle). Each wheel runs on the rut of the deepest earlier one "
    "(`snowjax.Rut`: Gawwad & Crolla's unloading line, thesis eq. 2.21, below it, the "
    "virgin law beyond), with an illustrative unloading modulus k_u = 1 MPa/m + "
    "5 MPa/m² · z_u. Left: the lowest point of each wheel below the original surface "
    "(dotted: the rut's depth after it); right: the resistance coefficient R/W."
)


@figure(
    "T.4",
    "wheels in one track: sinkage and resistance vs pass",
    RUT_CAPTION,
    ("2.21", "4.14", "4.16"),
)
def fig_ruts(ctx: Context) -> FigureResult:
    wheel = RigidWheel.thesis_tire()
    snow = WongSnow.thesis_fresh_snow()
    loads = np.stack([series for _, series in SERIES])
    res = multi_pass(wheel, snow, loads, SLIP, K_0, A_U)
    sinkage = 1e3 * np.asarray(res.sinkage)
    rut = 1e3 * np.asarray(res.rut_depth)
    coefficient = np.asarray(res.motion_resistance) / loads
    passes = np.arange(1, PASSES + 1)

    fig, (left, right) = subplots(1, 2, figsize=(10, 4.0))
    for k, (label, _) in enumerate(SERIES):
        left.plot(passes, sinkage[k], "o-", color=f"C{k}", label=label)
        left.plot(passes, rut[k], ":", color=f"C{k}")
        right.plot(passes, coefficient[k], "o-", color=f"C{k}", label=label)
    left.set_ylabel("sinkage below the original surface [mm]")
    right.set_ylabel("resistance coefficient R / W [-]")
    for ax in (left, right):
        ax.set_xlabel("pass")
        ax.grid(alpha=0.3)
    left.invert_yaxis()
    left.legend(fontsize=8)
    fig.suptitle(
        "Fig. T.4 (beyond the thesis): wheels in one track on the thesis snow", fontsize=10
    )
    fig.tight_layout()

    rows = [
        [label, int(p), float(loads[k, j]), float(sinkage[k, j]), float(rut[k, j]),
         float(coefficient[k, j]), int(np.asarray(res.status)[k, j])]
        for k, (label, _) in enumerate(SERIES)
        for j, p in enumerate(passes)
    ]  # fmt: skip
    cols = ["series", "pass", "load_N", "sinkage_mm", "rut_depth_mm", "R_over_W", "status"]
    statuses = {int(s) for s in np.asarray(res.status).ravel()}

    def listed(values, fmt):
        return ", ".join(format(v, fmt) for v in values)

    deepening = np.diff(rut[0])
    settled = int(np.argmax(deepening <= 1e-9)) + 2 if np.any(deepening <= 1e-9) else None
    comparison = (
        "Not in the thesis. Equal 5 kN wheels, sinkage by pass "
        f"{listed(sinkage[0], '.1f')} mm, R/W {listed(coefficient[0], '.3f')}: the rut "
        f"deepens by {listed(deepening, '.1f')} mm from pass to pass"
        + (
            f" (from pass {settled} on the wheels stay within the rut's elastic rebound "
            "and leave it as it was)"
            if settled is not None
            else ""
        )
        + f". 4 kN / 6 kN: {listed(sinkage[1], '.0f')} mm, R/W "
        f"{listed(coefficient[1], '.3f')}. CRREL 95-7 measured the resistance coefficient "
        "falling after the first wheel (its figure of resistance against the number of "
        "wheels through snow, not digitised here). Statuses: "
        + ", ".join(sorted(status_names(statuses)))
        + "."
    )
    ratio = coefficient[0, 1] / coefficient[0, 0]
    return FigureResult(
        fig,
        cols,
        rows,
        comparison,
        verdict=f"a second equal wheel has {ratio:.2f}x the first one's R/W",
    )
