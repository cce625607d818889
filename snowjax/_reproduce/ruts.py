"""Figures beyond the thesis for `snowjax reproduce`: wheels in one track on the thesis
snow, each on the rut the earlier ones left (`snowjax.multi_pass`), and a rut map under a
vehicle driving two laps of a circle (`snowjax.RutMap`, `snowjax.drive_path`).
"""

from __future__ import annotations

import numpy as np

from .._terrain.rut_map import RutMap
from .._terrain.wong import WongSnow
from .._wheel.geometry import RigidWheel
from .._wheel.passes import drive_path, multi_pass
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


# A kinematic four-wheel vehicle (wheelbase, track [m]) turning about a centre on its rear
# axle line, the rear axle's centre on a circle of RADIUS [m], two laps.
WHEELBASE, TRACK, RADIUS, WHEEL_LOAD = 2.5, 1.5, 6.0, 3500.0  # [m], [m], [m], [N]
CELL = 0.05  # [m]
WHEEL_NAMES = ("front left", "front right", "rear left", "rear right")

MAP_CAPTION = (
    "Beyond the thesis. A rut map (`snowjax.RutMap`, 5 cm cells) under a four-wheel "
    "vehicle (wheelbase 2.5 m, track 1.5 m, the 0.736 m × 0.235 m wheel of chapter 4 at "
    "3.5 kN and slip 0.2 on each corner, front region, classic shear) driven kinematically "
    "(`snowjax.drive_path`) twice round a circle of 6 m radius (the rear axle's centre) on "
    "the fresh snow of Table 4.1, counter-clockwise, in steps of about 6 cm. On this "
    "circle each rear wheel runs 0.45–0.57 m inside its front wheel's track, more than "
    "twice the wheel's width, so on the first lap all four wheels meet virgin snow; on the "
    "second lap each meets its own rut. Each wheel reads the map's mean depth across its width a "
    "wheel radius ahead of its axle and marks what it reached behind it; the unloading "
    "modulus is Fig. T.4's illustrative k_u. Left: the map's depth after the two laps; "
    "right: each wheel's lowest point below the original surface and its R/W along the "
    "distance the rear axle travelled."
)


@figure(
    "T.5",
    "a rut map: a vehicle meets its own ruts on the second lap",
    MAP_CAPTION,
    ("2.21", "4.14", "4.16"),
)
def fig_rut_map(ctx: Context) -> FigureResult:
    wheel = RigidWheel.thesis_tire()
    snow = WongSnow.thesis_fresh_snow()
    steps = 2 * (300 if ctx.small else 630)
    # Two laps, less the last 1.5 m, where the inner wheels' read points (a wheel radius
    # ahead) would reach the marks they made at the deeper depth of their second lap,
    # which begins a wheel radius before the first lap's end.
    angle = np.linspace(0.0, 4 * np.pi - 1.5 / RADIUS, steps)
    heading = angle + np.pi / 2
    centre = RADIUS * np.stack([np.cos(angle), np.sin(angle)], -1)  # rear axle's centre
    forward = np.stack([np.cos(heading), np.sin(heading)], -1)
    left = np.stack([-forward[:, 1], forward[:, 0]], -1)
    body = np.array([[WHEELBASE, TRACK / 2], [WHEELBASE, -TRACK / 2], [0, TRACK / 2],
                     [0, -TRACK / 2]])  # fmt: skip
    positions = (
        centre[:, None] + body[None, :, :1] * forward[:, None] + body[None, :, 1:] * left[:, None]
    )
    # The front wheels steer about the turning centre (the origin): headings normal to it.
    radial = np.arctan2(positions[..., 1], positions[..., 0])
    headings = radial + np.pi / 2
    half = RADIUS + WHEELBASE + 1.0
    grid = RutMap.empty((-half, half, -half, half), CELL, K_0, A_U)
    out = drive_path(wheel, snow, grid, positions, headings, WHEEL_LOAD, SLIP)
    sinkage = 1e3 * np.asarray(out.sinkage)
    coefficient = np.asarray(out.motion_resistance) / WHEEL_LOAD
    distance = RADIUS * angle
    depth = 1e3 * np.asarray(out.rut_map.depth)

    fig, (ax_map, ax_s) = subplots(1, 2, figsize=(11, 4.4))
    image = ax_map.imshow(depth.T, origin="lower", extent=(-half, half, -half, half), cmap="Blues")
    fig.colorbar(image, ax=ax_map, label="rut depth [mm]")
    ax_map.set_xlabel("x [m]")
    ax_map.set_ylabel("y [m]")
    ax_r = ax_s.twinx()
    for k, name in enumerate(WHEEL_NAMES):
        ax_s.plot(distance, sinkage[:, k], color=f"C{k}", label=name)
        ax_r.plot(distance, coefficient[:, k], ":", color=f"C{k}")
    ax_s.axvline(2 * np.pi * RADIUS, color="0.5", lw=0.8)
    ax_s.set_xlabel("distance travelled by the rear axle [m]")
    ax_s.set_ylabel("sinkage below the original surface [mm] (solid)")
    ax_r.set_ylabel("R / W [-] (dotted)")
    ax_s.legend(fontsize=8, loc="center left")
    fig.suptitle("Fig. T.5 (beyond the thesis): a rut map, two laps of a circle", fontsize=10)
    fig.tight_layout()

    stride = max(1, steps // 60)
    rows = [
        [float(distance[j]), name, float(sinkage[j, k]), float(1e3 * out.rut_depth[j, k]),
         float(coefficient[j, k]), int(np.asarray(out.status)[j, k])]
        for j in range(0, steps, stride)
        for k, name in enumerate(WHEEL_NAMES)
    ]  # fmt: skip
    cols = ["distance_m", "wheel", "sinkage_mm", "rut_seen_mm", "R_over_W", "status"]
    statuses = {int(s) for s in np.asarray(out.status).ravel()}
    lap1, lap2 = slice(steps // 8, steps // 2 - steps // 16), slice(5 * steps // 8, steps)
    first, second = coefficient[lap1].mean(0), coefficient[lap2].mean(0)
    comparison = (
        "Not in the thesis. First lap, R/W per wheel "
        + ", ".join(f"{v:.3f}" for v in first)
        + f" (sinkage {sinkage[lap1].mean():.1f} mm); second lap, in their own ruts, "
        + ", ".join(f"{v:.3f}" for v in second)
        + f" (lowest point {sinkage[lap2].mean():.1f} mm below the original surface). The "
        "second lap repeats `multi_pass`'s second pass (tests/test_rut_map.py). Memory: "
        f"{grid.depth.shape[0]} × {grid.depth.shape[1]} cells, {grid.nbytes / 2**20:.1f} MiB. "
        "Statuses: " + ", ".join(sorted(status_names(statuses))) + "."
    )
    return FigureResult(
        fig,
        cols,
        rows,
        comparison,
        verdict=f"on the second lap R/W falls to {second.mean() / first.mean():.2f}x",
    )
