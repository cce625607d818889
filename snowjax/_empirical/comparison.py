"""Side-by-side comparison of every motion-resistance model of chapter 2 with the rigid wheel
(table and figure).
"""

from __future__ import annotations

import dataclasses
import math
from typing import cast

import jax.numpy as jnp
import numpy as np

from .._wheel.model import _as_model, _takes_model
from .common import (
    ICE_DENSITY,
    _positive,
)
from .models import (
    bekker_rolling_resistance,
    bekker_wheel_sinkage,
    richmond_resistance,
    van_es_rolling_resistance,
)
from .traction import brixius as _brixius

# Default sigma_i for the comparison: the compaction law p = sigma_i exp(-lambda r^2) with
# lambda = 1 reaches rho_f = 500 kg/m^3 at 210 kPa — CRREL's final-density rule for tyres
# with a peak contact pressure up to 210 kPa (Richmond 1995, CRREL Report 95-7).
_CRREL_FINAL_DENSITY = 500.0  # [kg/m^3]
_CRREL_PRESSURE = 210e3  # [Pa]
DEFAULT_ICE_PRESSURE = _CRREL_PRESSURE * math.exp((ICE_DENSITY / _CRREL_FINAL_DENSITY - 1) ** 2)


@dataclasses.dataclass(frozen=True)
class SnowCover:
    """The snow cover that the empirical models of `compare_motion_resistance` read
    (Richmond 2.23, Van Es 2.26).

    - `density`: initial density rho_0 [kg/m^3] (default 200, Shoop's laboratory snow).
    - `depth`: snow depth h_0 [m] (default None: z_w of the Wong snow).
    - `ice_pressure`: sigma_i of Van Es's compaction law [Pa] (default 421 kPa: the law
      reaches CRREL's 500 kg/m^3 at 210 kPa; an assumption, not a thesis value).
    - `grain_index`: lambda of Van Es's compaction law [-] (default 1).
    - `hard_surface_coefficient`: f_r of Van Es's D_r = f_r W [-] (default 0: only the
      snow's share).
    """

    density: float = 200.0
    depth: float | None = None
    ice_pressure: float = DEFAULT_ICE_PRESSURE
    grain_index: float = 1.0
    hard_surface_coefficient: float = 0.0


@dataclasses.dataclass(frozen=True)
class BrixiusTyre:
    """Brixius's inputs (eq. 2.20) for `compare_motion_resistance`'s `brixius` column:
    the soil's cone index [Pa] and the tyre's section height [m] and deflection [m]."""

    cone_index: float
    section_height: float
    deflection: float = 0.0


_MOVED_TO_COVER = {
    "density": "cover=SnowCover(density=...)",
    "snow_depth": "cover=SnowCover(depth=...)",
    "ice_pressure": "cover=SnowCover(ice_pressure=...)",
    "grain_index": "cover=SnowCover(grain_index=...)",
    "hard_surface_coefficient": "cover=SnowCover(hard_surface_coefficient=...)",
    "cone_index": "brixius=BrixiusTyre(cone_index, section_height, deflection)",
    "section_height": "brixius=BrixiusTyre(cone_index, section_height, deflection)",
    "deflection": "brixius=BrixiusTyre(cone_index, section_height, deflection)",
}


@_takes_model(positional=1, **_MOVED_TO_COVER)
def compare_motion_resistance(
    loads=None,
    *,
    wheel=None,
    wong_snow=None,
    bekker_snow=None,
    slip: float = 0.0,
    cover: SnowCover = SnowCover(),
    brixius: BrixiusTyre | None = None,
):
    """Motion resistance versus wheel load for every model of the project, one snow, one tyre.

    Models (all in N, per wheel):

    - `rigid_wheel`: the rigid-wheel equilibrium of chapter 4, eq. (4.16), with the Wong
      snow `wong_snow` at slip `slip` (via `snowjax.solve_wheel`).
    - `bekker`: Bekker's closed form (2.25) with the Bekker fit `bekker_snow` (unlimited
      depth).  `bekker_sinkage` (its z0) is reported too.
    - `richmond`: Richmond (2.23) with rho_0 = `cover.density` and the contact arc
      a = r theta_0, theta_0 the rigid wheel's entry angle (the rut the same tyre makes
      in the same snow).  Without the rigid-wheel solver, a = r arccos(1 - z0/r) from
      Bekker's sinkage z0 instead (flagged in `table["richmond_contact"]`).
    - `van_es`: Van Es (2.26) with D_r = `cover.hard_surface_coefficient` W, D_d = 0,
      rho_0 = `cover.density`, h_0 = `cover.depth`, lambda = `cover.grain_index`,
      sigma_i = `cover.ice_pressure`, and the final density from mass conservation in
      the rut of the rigid wheel: rho_f = min(rho_0 h_0 / (h_0 - z0), rho_i), z0 the
      rigid-wheel sinkage.  The default sigma_i = 421 kPa makes Van Es's compaction law
      reach 500 kg/m^3 at 210 kPa — CRREL's final-density rule for tyres with peak
      contact pressure up to 210 kPa (Richmond 1995, CRREL Report 95-7).  It is an
      assumption, not a thesis value.
    - `brixius` (only when `brixius` is given — the thesis gives no cone index for its
      snow): mu_R W from eq. (2.20) (`variant="thesis"`) with the `BrixiusTyre`'s cone
      index, section height and deflection, at slip `slip`.

    Defaults: the thesis tyre (`RigidWheel.thesis_tire()`: D 0.736 m, b 0.235 m), the
    thesis's fresh snow (`WongSnow.thesis_fresh_snow()`, and its Bekker fit
    `BekkerSoil.thesis_lab_snow()`: Shoop's 200 kg/m^3 laboratory snow), snow depth
    h_0 = z_w = 0.2 m, loads 1–8 kN.

    **Arguments:**

    - `loads`: wheel loads [N] (default 15 loads from 1 to 8 kN).
    - `wheel`: `snowjax.RigidWheel`; `wong_snow`: `snowjax.WongSnow`, or a
      `ContactModel` of one (e.g. another shear law); `bekker_snow`:
      `snowjax.BekkerSoil`.
    - `slip`: slip of the rigid wheel [-] (default 0, a towed wheel).
    - `cover`: `SnowCover(density [kg/m^3], depth [m], ice_pressure [Pa], grain_index
      [-], hard_surface_coefficient [-])`, the snow cover of the empirical models.
    - `brixius`: `BrixiusTyre(cone_index [Pa], section_height [m], deflection [m])` for
      the Brixius column, or None (default: no Brixius column).

    **Returns:** `(table, figure)`: `table` is a dict of NumPy arrays keyed `"load"` [N]
    and one key per model [N] (NaN where the rigid-wheel solve neither converged nor
    bottomed out), plus `"rigid_wheel_sinkage"`, `"bekker_sinkage"`, `"contact_length"`
    [m], `"final_density"` [kg/m^3], `"rigid_wheel_status"` (`snowjax.Status` codes) and
    boolean `"<model>_in_range"` masks: Bekker z0 <= min(D/6, h_0); rigid wheel
    converged (not resting on the base); Van Es rho_f below ice density.  `figure` is a
    matplotlib `Figure` (Agg canvas, not shown) of motion resistance and resistance
    coefficient versus load; open markers are outside the stated range.
    """
    from .._terrain.bekker import BekkerSoil
    from .._terrain.wong import WongSnow
    from .._wheel.geometry import RigidWheel

    if loads is None:
        loads = np.linspace(1e3, 8e3, 15)
    loads = np.asarray(loads, dtype=float)
    _positive("loads", loads, "N")
    wheel = RigidWheel.thesis_tire() if wheel is None else wheel
    wong_snow = WongSnow.thesis_fresh_snow() if wong_snow is None else wong_snow
    bekker_snow = BekkerSoil.thesis_lab_snow() if bekker_snow is None else bekker_snow
    diameter = float(wheel.diameter)
    radius = diameter / 2
    width = float(wheel.width)
    density = cover.density
    wong = _as_model(wong_snow, "wong_snow").terrain
    h0 = float(cast(WongSnow, wong).z_w) if cover.depth is None else float(cover.depth)
    _positive("snow_depth", h0, "m")

    table: dict[str, np.ndarray] = {"load": loads}

    bekker_args = (diameter, width, bekker_snow.k_c, bekker_snow.k_phi, bekker_snow.n)
    table["bekker"] = np.asarray(bekker_rolling_resistance(loads, *bekker_args))
    table["bekker_sinkage"] = np.asarray(bekker_wheel_sinkage(loads, *bekker_args))

    solve_wheel = _find_solve_wheel()
    if solve_wheel is not None:
        state = solve_wheel(wheel, wong_snow, jnp.asarray(loads), jnp.asarray(slip))
        status = np.asarray(state.status)
        # converged (0) or resting on the base (1, sinkage = z_w): usable; anything else
        # (invalid, not converged, entry-angle limit) is reported as NaN, never plotted.
        usable = (status == 0) | (status == 1)
        table["rigid_wheel"] = np.where(usable, np.asarray(state.motion_resistance), np.nan)
        table["rigid_wheel_sinkage"] = np.where(usable, np.asarray(state.sinkage), np.nan)
        table["rigid_wheel_status"] = status
        entry_angle = np.where(usable, np.asarray(state.entry_angle), np.nan)
        rut = table["rigid_wheel_sinkage"]
        table["richmond_contact"] = np.array("rigid-wheel entry angle")
    else:
        z_b = np.minimum(table["bekker_sinkage"], radius)
        entry_angle = np.arccos(1 - z_b / radius)
        rut = table["bekker_sinkage"]
        table["richmond_contact"] = np.array("Bekker sinkage (rigid-wheel solver missing)")

    table["contact_length"] = radius * entry_angle
    arc = np.where(np.isfinite(entry_angle), table["contact_length"], 0.0)
    table["richmond"] = np.where(
        np.isfinite(entry_angle), np.asarray(richmond_resistance(density, arc, width)), np.nan
    )

    known = np.isfinite(rut)
    rut = np.minimum(np.where(known, rut, 0.0), h0)
    rho_f = np.where(rut < h0, density * h0 / np.maximum(h0 - rut, 1e-300), ICE_DENSITY)
    rho_f = np.clip(rho_f, density, ICE_DENSITY)
    van_es = van_es_rolling_resistance(
        loads,
        width,
        h0,
        density,
        rho_f,
        cover.ice_pressure,
        cover.hard_surface_coefficient,
        grain_index=cover.grain_index,
    )
    table["final_density"] = np.where(known, rho_f, np.nan)
    table["van_es"] = np.where(known, np.asarray(van_es), np.nan)

    if brixius is not None:
        cone, deflection, height = brixius.cone_index, brixius.deflection, brixius.section_height
        mu_r = _brixius(cone, width, diameter, loads, deflection, height, slip)
        table["brixius"] = np.asarray(mu_r.motion_resistance) * loads

    # where each model is inside the range its source states (open markers otherwise)
    table["bekker_in_range"] = table["bekker_sinkage"] <= min(diameter / 6, h0)
    if "rigid_wheel" in table:
        table["rigid_wheel_in_range"] = table["rigid_wheel_status"] == 0
    table["richmond_in_range"] = np.isfinite(table["richmond"])
    table["van_es_in_range"] = np.isfinite(table["van_es"]) & (table["final_density"] < ICE_DENSITY)
    figure = _comparison_figure(
        table,
        wheel_label=f"D {diameter:.3f} m, b {width:.3f} m",
        snow_label=f"rho0 {density:.0f} kg/m^3, h0 {h0:.2f} m",
    )
    return table, figure


_MODEL_LABELS = {
    "rigid_wheel": "rigid wheel, Wong snow (4.16)",
    "bekker": "Bekker closed form (2.25)",
    "richmond": "Richmond (2.23)",
    "van_es": "Van Es (2.26)",
    "brixius": "Brixius mu_R W (2.20)",
}


def _find_solve_wheel():
    try:
        from .._wheel import equilibrium as _wheel  # noqa: PLC0415
    except ImportError:
        return None
    return getattr(_wheel, "solve_wheel", None)


def _comparison_figure(table, *, wheel_label: str, snow_label: str):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(10, 4.2), layout="constrained")
    FigureCanvasAgg(figure)
    ax_force, ax_coeff = figure.subplots(1, 2)
    load_kn = table["load"] / 1e3
    for key, label in _MODEL_LABELS.items():
        if key not in table:
            continue
        force = np.asarray(table[key], dtype=float)
        inside = np.asarray(table.get(f"{key}_in_range", np.ones_like(force, dtype=bool)))
        for ax, y in ((ax_force, force), (ax_coeff, force / table["load"])):
            (line,) = ax.plot(load_kn, y, label=label)
            ax.plot(load_kn[inside], y[inside], "o", ms=4, color=line.get_color())
            ax.plot(load_kn[~inside], y[~inside], "o", ms=4, mfc="none", color=line.get_color())
    ax_force.set_xlabel("wheel load W [kN]")
    ax_force.set_ylabel("motion resistance [N]")
    ax_force.set_title("Motion resistance vs load")
    ax_coeff.set_xlabel("wheel load W [kN]")
    ax_coeff.set_ylabel("resistance coefficient R / W [-]")
    ax_coeff.set_title("Resistance coefficient vs load")
    for ax in (ax_force, ax_coeff):
        ax.grid(True, alpha=0.3)
    ax_force.legend(fontsize=8)
    figure.suptitle(
        f"Tyre {wheel_label}; snow {snow_label}   (open markers: outside the model's stated range)",
        fontsize=10,
    )
    return figure
