"""The models `snowjax validate` compares with Shoop (2001) Table 11 (see
`snowjax._validate.validate` for the data, the method and the defaults)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

__all__ = ["ValidationModel", "validation_models", "wheel_validation_model"]

DEFAULT_WHEEL_LOAD = 6800.0  # [N], CRREL 95-7 Table 2 (interpretation, see module docs)
DEFAULT_TYRE_WIDTH = 0.235  # [m], assumption
CIV_FINAL_DENSITY = 500.0  # [kg/m^3], CRREL 95-7: the value used for the CIV's tyres
CIV_INFLATION = 103e3  # [Pa], CRREL 95-7 Table 2: the CIV's tyres at the lower pressure
CIV_SECTION_RATIO = 0.75  # section height / width [-], an assumption (a 75-series tyre)

# ----------------------------------------------------------------------------------------
# models
# ----------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class ValidationModel:
    """A model compared with Table 11.

    `evaluate(rows, grid)` returns `(sinkage, coefficient)`, each of shape
    `(n_rows, len(grid))` (or `None` for a quantity the model does not predict); `grid`
    is the grid of the calibrated parameter, 1-D or (G, k) for k parameters together
    (`None`: nothing to calibrate, shape `(n_rows, 1)`).  `fit_target` is the quantity
    the parameter is fitted to (`"sinkage"`, `"coefficient"`, or `"both"`: their squared
    errors in units of `BOTH_SCALES`).
    """

    key: str
    label: str
    equations: str
    evaluate: Callable
    grid: np.ndarray | None = None
    fit_target: str | None = None
    parameter: str = ""
    note: str = ""


def _wong_terrain(rows, grid, diameter):
    from .._terrain.wong import WongSnow

    p_w = np.asarray(grid)[None, :]
    return WongSnow(
        p_w=p_w,
        z_w=rows["snow_depth_m"][:, None],
        cohesion=0.2165 * p_w,
        tan_phi=0.0787,
        shear_modulus=diameter / 73.6,
    )


def _wong_pit_terrain(rows, grid, diameter):
    """Wong snow from the row's depth and density (`WongSnow.from_snow_pit`: z_w = h (1 -
    rho0 / rho_f), CRREL 95-7 eq. 1) with Table 4.1's ratios; `grid` rows (p_w [Pa],
    rho_f [kg/m^3])."""
    from .._terrain.wong import WongSnow

    p_w, rho_f = np.asarray(grid)[None, :, 0], np.asarray(grid)[None, :, 1]
    return WongSnow.from_snow_pit(
        rows["snow_depth_m"][:, None],
        rows["density_kg_m3"][:, None],
        p_w=p_w,
        cohesion=0.2165 * p_w,
        tan_phi=0.0787,
        shear_modulus=diameter / 73.6,
        final_density=rho_f,
    )


# (p_w [Pa], rho_f [kg/m^3]) of the two-parameter snow: 16 x 16 points (rho_f in steps
# of 67 kg/m^3).
PIT_GRID = np.stack(
    [
        g.ravel()
        for g in np.meshgrid(
            np.geomspace(5e3, 300e3, 16), np.linspace(400.0, 1400.0, 16), indexing="ij"
        )
    ],
    axis=1,
)


def _civ_tire(diameter, width):
    """The CIV's front Michelin XCH4 as a `DeflectingTire`: p_i = 103 kPa (CRREL 95-7
    Table 2), p_c = 0 and a section height of 0.75 b (assumptions: neither is in the
    stored sources), without flexing resistance (f_h = 0): Table 11's resistances are
    "only the portion of the resistance due to the deformation of the terrain" (Shoop
    2001, the text above the table), the vehicle's resistance on pavement subtracted."""
    from .._wheel.tire import DeflectingTire

    return DeflectingTire(diameter, width, CIV_SECTION_RATIO * width, CIV_INFLATION, 0.0)


def _bekker_terrain(rows, grid, diameter):
    from .._terrain.bekker import BekkerSoil

    lab = BekkerSoil.thesis_lab_snow()
    s = np.asarray(grid)[None, :]
    return BekkerSoil(
        n=lab.n,
        k_c=lab.k_c * s,
        k_phi=lab.k_phi * s,
        cohesion=lab.cohesion,
        tan_phi=lab.tan_phi,
        shear_modulus=lab.shear_modulus,
    )


def wheel_validation_model(
    key: str,
    label: str,
    make_terrain: Callable,
    grid: np.ndarray,
    parameter: str,
    *,
    wheel_load: float = DEFAULT_WHEEL_LOAD,
    tyre_width: float = DEFAULT_TYRE_WIDTH,
    make_wheel: Callable | None = None,
    fit_target: str = "sinkage",
    note: str = "",
) -> ValidationModel:
    """The chapter-4 wheel (`snowjax.solve_wheel`, towed: slip 0, classic shear) on any
    terrain: `make_terrain(rows, grid, diameter)` must return a `snowjax` terrain whose
    leaves broadcast to `(n_rows, len(grid))` (or `(1, len(grid))`); `make_wheel(diameter,
    width)` the wheel (default `RigidWheel`; e.g. a `DeflectingTire`).  The parameter on
    `grid` (1-D, or (G, k) for k parameters together) is fitted by leave-one-out to the
    measured sinkage (`fit_target="sinkage"`), or to sinkage and R/W together ("both":
    squared errors in units of `BOTH_SCALES`).  Elements that neither converge nor
    bottom out are NaN (and never chosen)."""

    def evaluate(rows, grid):
        import jax.numpy as jnp

        from .._wheel.equilibrium import solve_wheel
        from .._wheel.geometry import RigidWheel

        diameter = 2 * float(rows["radius_m"][0])
        wheel = (make_wheel or RigidWheel)(diameter, tyre_width)
        terrain = make_terrain(rows, grid, diameter)
        st = solve_wheel(wheel, terrain, jnp.asarray(wheel_load), jnp.asarray(0.0))
        status = np.asarray(st.status)
        usable = (status == 0) | (status == 1)
        shape = (len(rows["row"]), len(grid))
        z = np.broadcast_to(np.where(usable, np.asarray(st.sinkage), np.nan), shape)
        mu = np.broadcast_to(
            np.where(usable, np.asarray(st.motion_resistance) / wheel_load, np.nan), shape
        )
        return z, mu

    return ValidationModel(
        key=key,
        label=label,
        equations="rigid wheel, sinkage-vs-load equilibrium (4.14), resistance (4.16)",
        evaluate=evaluate,
        grid=np.asarray(grid),
        fit_target=fit_target,
        parameter=parameter,
        note=note,
    )


def validation_models(
    *, wheel_load: float = DEFAULT_WHEEL_LOAD, tyre_width: float = DEFAULT_TYRE_WIDTH
) -> list[ValidationModel]:
    """The models compared by [`snowjax.validate`][] (see the module docstring)."""
    from .._empirical.crrel import crrel_contact_arc, crrel_wheel
    from .._empirical.models import (
        bekker_rolling_resistance,
        bekker_wheel_sinkage,
        richmond_resistance,
        van_es_compaction_resistance,
    )
    from .._terrain.bekker import BekkerSoil

    lab = BekkerSoil.thesis_lab_snow()
    w_n, b = wheel_load, tyre_width

    def wheel_model(*args, **kwargs):  # the chapter-4 wheel at this load and width
        return wheel_validation_model(*args, wheel_load=w_n, tyre_width=b, **kwargs)

    def n_rows(rows):
        return len(rows["row"])

    def baseline(rows, grid):
        # never called: `validate` predicts each row by the mean of the other rows.
        return None, None

    def crrel_fixed(rows, grid):
        out = crrel_wheel(
            rows["snow_depth_m"],
            rows["density_kg_m3"],
            rows["radius_m"],
            b,
            w_n,
            final_density=CIV_FINAL_DENSITY,
        )
        return (np.asarray(out.sinkage)[:, None], np.asarray(out.resistance_coefficient)[:, None])

    def crrel_fitted(rows, grid):
        out = crrel_wheel(
            rows["snow_depth_m"][:, None],
            rows["density_kg_m3"][:, None],
            rows["radius_m"][:, None],
            b,
            w_n,
            final_density=grid[None, :],
        )
        return np.asarray(out.sinkage), np.asarray(out.resistance_coefficient)

    def richmond_measured(rows, grid):
        a = crrel_contact_arc(rows["radius_m"], rows["sinkage_m"])
        r = richmond_resistance(rows["density_kg_m3"], a, b)
        return None, (np.asarray(r) / w_n)[:, None]

    def bekker_closed(rows, grid):
        d = 2 * float(rows["radius_m"][0])
        s = np.asarray(grid)
        z = np.asarray(bekker_wheel_sinkage(w_n, d, b, lab.k_c * s, lab.k_phi * s, lab.n))
        r = np.asarray(bekker_rolling_resistance(w_n, d, b, lab.k_c * s, lab.k_phi * s, lab.n))
        shape = (n_rows(rows), len(s))
        return np.broadcast_to(z, shape), np.broadcast_to(r / w_n, shape)

    def van_es(rows, grid):
        h = rows["snow_depth_m"][:, None]
        rho0 = rows["density_kg_m3"][:, None]
        d_c = van_es_compaction_resistance(b, h, rho0, CIV_FINAL_DENSITY, grid[None, :])
        return None, np.asarray(d_c) / w_n

    return [
        ValidationModel(
            "baseline",
            "baseline: mean of the training rows",
            "-",
            baseline,
            note="predicts every held-out row by the mean of the others",
        ),
        ValidationModel(
            "crrel",
            "CRREL shallow snow (rho_f = 500 kg/m^3)",
            "CRREL 95-7 eq. 1 (z = h(1 - rho0/rho_f)) + eq. 4 (= thesis 2.23) on the "
            "arc a = r arccos(1 - z/r)",
            crrel_fixed,
            note="no calibration: rho_f = 500 kg/m^3 is CRREL 95-7's value for the CIV",
        ),
        ValidationModel(
            "crrel_fit",
            "CRREL shallow snow, rho_f fitted",
            "as above",
            crrel_fitted,
            grid=np.linspace(300.0, 917.0, 618),
            fit_target="sinkage",
            parameter="rho_f [kg/m^3]",
        ),
        ValidationModel(
            "richmond_measured_rut",
            "Richmond (2.23) on the measured rut",
            "R = 21.313 (rho0 w a)^1.1918, a = r arccos(1 - z_measured/r)",
            richmond_measured,
            note="uses the measured sinkage as input: tests the resistance law alone",
        ),
        wheel_model(
            "wheel_wong",
            "chapter-4 wheel, Wong snow (z_w = h)",
            _wong_terrain,
            np.geomspace(2e3, 400e3, 81),
            "p_w [Pa]",
            note="Table 4.1 ratios c/p_w = 0.2165, tan phi = 0.0787, K = D/73.6; p_w fitted",
        ),
        wheel_model(
            "tire_wong",
            "deflecting tyre (103 kPa), Wong snow (z_w = h)",
            _wong_terrain,
            np.geomspace(2e3, 400e3, 81),
            "p_w [Pa]",
            make_wheel=_civ_tire,
            note="DeflectingTire p_i = 103 kPa (CRREL 95-7 Table 2), p_c = 0 and section "
            "height 0.75 b (assumed); snow as the row above; p_w fitted",
        ),
        wheel_model(
            "wheel_wong_pit",
            "chapter-4 wheel, Wong snow from depth and density, 2 parameters",
            _wong_pit_terrain,
            PIT_GRID,
            "p_w [Pa], rho_f [kg/m^3]",
            fit_target="both",
            note="z_w = h (1 - rho0 / rho_f) (CRREL 95-7 eq. 1); Table 4.1 ratios; p_w and "
            "rho_f fitted to sinkage and R/W together",
        ),
        wheel_model(
            "tire_wong_pit",
            "deflecting tyre (103 kPa), Wong snow from depth and density, 2 parameters",
            _wong_pit_terrain,
            PIT_GRID,
            "p_w [Pa], rho_f [kg/m^3]",
            make_wheel=_civ_tire,
            fit_target="both",
            note="the tyre of the row above on the snow of the row above",
        ),
        wheel_model(
            "wheel_bekker",
            "chapter-4 wheel, Bekker snow (unlimited depth)",
            _bekker_terrain,
            np.geomspace(0.1, 100.0, 61),
            "scale of (k_c, k_phi)",
            note="thesis lab snow n = 1.0707, k_c, k_phi scaled by a fitted factor",
        ),
        ValidationModel(
            "bekker",
            "Bekker closed form (2.24/2.25)",
            "z0 and R_c of (2.25)",
            bekker_closed,
            grid=np.geomspace(0.1, 100.0, 121),
            fit_target="sinkage",
            parameter="scale of (k_c, k_phi)",
            note="thesis lab snow n = 1.0707, k_c, k_phi scaled by a fitted factor",
        ),
        ValidationModel(
            "van_es",
            "Van Es (2.26), D_c only",
            "D_c with rho_f = 500 kg/m^3, lambda = 1",
            van_es,
            grid=np.geomspace(1e4, 1e8, 161),
            fit_target="coefficient",
            parameter="sigma_i [Pa]",
            note="sigma_i fitted to the resistance coefficient; D_r = D_d = 0",
        ),
    ]
