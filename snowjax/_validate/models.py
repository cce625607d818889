"""The models `snowjax validate` compares with Shoop (2001) Table 11 (see
`snowjax._validate.validate` for the data, the method and the defaults).

Each model is a **prediction** (every parameter from the literature or from other data,
nothing taken from the rows it is scored on; the rows' snow depth and density are the
conditions, given as for any prediction) or a **calibration** (parameters chosen on the
rows, each within bounds taken from a cited source, scored by cross-validation that refits
them per fold).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from .._constants import PLATE_RULE_P_W, THESIS_P_W
from .._empirical.common import ICE_DENSITY
from .._wheel.model import _renamed

__all__ = ["ParameterBound", "ValidationModel", "validation_models", "wheel_validation_model"]

DEFAULT_WHEEL_LOAD = 6800.0  # [N], CRREL 95-7 Table 2 (interpretation, see module docs)
DEFAULT_TYRE_WIDTH = 0.235  # [m], assumption
CIV_FINAL_DENSITY = 500.0  # [kg/m^3], CRREL 95-7: the value used for the CIV's tyres
CIV_INFLATION = 103e3  # [Pa], CRREL 95-7 Table 2: the CIV's tyres at the lower pressure
CIV_SECTION_RATIO = 0.75  # section height / width [-], an assumption (a 75-series tyre)


@dataclasses.dataclass(frozen=True)
class ParameterBound:
    """The range a calibrated parameter may take, and where it comes from.

    - `name`: the parameter, with its unit ("rho_f [kg/m^3]").
    - `lower`, `upper`: the range (SI), the ends of the calibration's grid.
    - `source`: the cited source of the range.
    """

    name: str
    lower: float
    upper: float
    source: str


# rho_f: CRREL 95-7 (Richmond, Shoop & Blaisdell 1995, beside eq. 1) gives the final
# density of snow under a tyre or track by its peak contact pressure: 500 kg/m^3 up to
# 210 kPa, 550, 600 and 650 kg/m^3 above 210, 350 and 700 kPa.
FINAL_DENSITY = ParameterBound(
    "rho_f [kg/m^3]",
    500.0,
    650.0,
    "CRREL 95-7 (final density 500-650 kg/m^3 by peak contact pressure)",
)
# p_w: the thesis's two values for fresh snow, Wong's plate rule on its plate test
# (Table 2.1: 12.92 kPa) and the value that makes its Table 4.1 entry angle the 5 kN
# no-shear equilibrium of its tyre (85.55 kPa; `WongSnow.thesis_fresh_snow`).
WONG_P_W = ParameterBound(
    "p_w [Pa]",
    PLATE_RULE_P_W,
    THESIS_P_W,
    "Sankapalli (2004): Table 2.1 (plate rule) to Table 4.1 (12.9-85.6 kPa)",
)
P_W_GRID = np.geomspace(WONG_P_W.lower, WONG_P_W.upper, 21)  # steps of 10 %
RHO_F_GRID = np.linspace(FINAL_DENSITY.lower, FINAL_DENSITY.upper, 7)  # steps of 25 kg/m^3
# (p_w [Pa], rho_f [kg/m^3]) of the two-parameter snow.
PIT_GRID = np.stack([g.ravel() for g in np.meshgrid(P_W_GRID, RHO_F_GRID, indexing="ij")], 1)


@dataclasses.dataclass(frozen=True)
class ValidationModel:
    """A model compared with Table 11.

    `evaluate(rows, grid)` returns `(sinkage, coefficient)`, each of shape
    `(n_rows, len(grid))` (or `None` for a quantity the model does not predict); `grid`
    is the grid of the calibrated parameters, 1-D or (G, k) for k parameters together,
    whose ends are the `bounds` (`None`: a prediction, shape `(n_rows, 1)`).
    `fit_target` is the quantity a calibration is fitted to (`"sinkage"`,
    `"coefficient"`, or `"both"`: their squared errors in units of `BOTH_SCALES`).

    - `fixed`: the parameters set without the rows, and their sources.
    - `bounds`: a calibration's `ParameterBound` per grid column.
    - `row_inputs`: measured quantities of the scored rows the model takes as input
      beyond their snow's depth and density (e.g. the measured sinkage).
    - `compare_to`: the key of the rigid-wheel model on the same snow and grid, for a
      tyre's own contribution (tyre minus rim at the parameters chosen).
    """

    key: str
    label: str
    equations: str
    evaluate: Callable
    grid: np.ndarray | None = None
    fit_target: str | None = None
    parameter: str = ""
    note: str = ""
    fixed: str = ""
    bounds: tuple[ParameterBound, ...] = ()
    row_inputs: str = ""
    compare_to: str | None = None

    @property
    def kind(self) -> str:
        """`"calibration"` (parameters fitted on the rows), `"prediction"`, or
        `"baseline"` (the mean of the training rows)."""
        if self.key == "baseline":
            return "baseline"
        return "prediction" if self.grid is None else "calibration"


# ----------------------------------------------------------------------------------------
# models
# ----------------------------------------------------------------------------------------


def _strength(p_w, diameter):
    """Table 4.1's ratios: c = 0.2165 p_w, tan phi = 0.0787, K = D / 73.6."""
    return {"cohesion": 0.2165 * p_w, "tan_phi": 0.0787, "shear_modulus": diameter / 73.6}


def _wong_terrain(rows, grid, diameter):
    """Wong snow on a base at the snow's depth (z_w = h), p_w on `grid`."""
    from .._terrain.wong import WongSnow

    p_w = np.asarray(grid)[None, :]
    return WongSnow(p_w=p_w, z_w=rows["snow_depth_m"][:, None], **_strength(p_w, diameter))


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
        final_density=rho_f,
        **_strength(p_w, diameter),
    )


# The prediction's snow: the thesis's plate rule p_w and CRREL's rho_f for the CIV.
PREDICTED_PIT_SNOW = np.array([[PLATE_RULE_P_W, CIV_FINAL_DENSITY]])


def _predicted_pit_terrain(rows, grid, diameter):
    return _wong_pit_terrain(rows, PREDICTED_PIT_SNOW, diameter)


def _civ_tire(diameter, width):
    """The CIV's front Michelin XCH4 as a `DeflectingTire`: p_i = 103 kPa (CRREL 95-7
    Table 2), p_c = 0 and a section height of 0.75 b (assumptions: neither is in the
    stored sources), without flexing resistance (f_h = 0): Table 11's resistances are
    "only the portion of the resistance due to the deformation of the terrain" (Shoop
    2001, the text above the table), the vehicle's resistance on pavement subtracted."""
    from .._wheel.tire import DeflectingTire

    return DeflectingTire(diameter, width, CIV_SECTION_RATIO * width, CIV_INFLATION, 0.0)


def _bekker_lab_snow(rows, grid, diameter):
    from .._terrain.bekker import BekkerSoil

    return BekkerSoil.thesis_lab_snow()


@_renamed(
    5,
    "wheel_validation_model(key, label, make_terrain, grid, parameter, ...)",
    **{
        name: f"dataclasses.replace(model, {name}=...) on the ValidationModel it returns"
        for name in ("note", "fixed", "compare_to")
    },
)
def wheel_validation_model(
    key: str,
    label: str,
    make_terrain: Callable,
    grid: np.ndarray | None,
    parameter: str,
    *,
    wheel_load: float = DEFAULT_WHEEL_LOAD,
    tyre_width: float = DEFAULT_TYRE_WIDTH,
    make_wheel: Callable | None = None,
    fit_target: str = "sinkage",
    bounds: tuple[ParameterBound, ...] = (),
) -> ValidationModel:
    """The chapter-4 wheel (`snowjax.solve_wheel`, towed: slip 0, classic shear) on any
    terrain: `make_terrain(rows, grid, diameter)` must return a `snowjax` terrain whose
    leaves broadcast to `(n_rows, len(grid))` (or `(1, len(grid))`); `make_wheel(diameter,
    width)` the wheel (default `RigidWheel`; e.g. a `DeflectingTire`), at load
    `wheel_load` [N] and width `tyre_width` [m].  With a `grid` (1-D, or (G, k) for k
    parameters together, its ends the `bounds`; `parameter` names its columns, with
    units) the model is a calibration, fitted per fold to the measured sinkage
    (`fit_target="sinkage"`), or to sinkage and R/W together ("both": squared errors in
    units of `BOTH_SCALES`); without one (`None`) a prediction (`make_terrain` gets a
    grid of one point, unused).  Elements that neither converge nor bottom out are NaN
    (and never chosen).  The table's texts (`note`, `fixed`, `compare_to`) are set on
    the returned frozen `ValidationModel` with `dataclasses.replace`."""

    def evaluate(rows, points):
        import jax.numpy as jnp

        from .._wheel.equilibrium import solve_wheel
        from .._wheel.geometry import RigidWheel

        diameter = 2 * float(rows["radius_m"][0])
        wheel = (make_wheel or RigidWheel)(diameter, tyre_width)
        terrain = make_terrain(rows, points, diameter)
        st = solve_wheel(wheel, terrain, jnp.asarray(wheel_load), jnp.asarray(0.0))
        status = np.asarray(st.status)
        usable = (status == 0) | (status == 1)
        shape = (len(rows["row"]), len(points))
        z = np.broadcast_to(np.where(usable, np.asarray(st.sinkage), np.nan), shape)
        mu = np.broadcast_to(
            np.where(usable, np.asarray(st.motion_resistance) / wheel_load, np.nan), shape
        )
        return z, mu

    return ValidationModel(
        key=key,
        label=label,
        equations="chapter-4 wheel, sinkage-vs-load equilibrium (4.14), resistance (4.16)",
        evaluate=evaluate,
        grid=None if grid is None else np.asarray(grid),
        fit_target=None if grid is None else fit_target,
        parameter=parameter,
        bounds=bounds,
    )


# The order of `validate`'s table: the baseline, the empirical models, then each snow's
# chapter-4 wheel followed by its deflecting tyre (the Bekker closed form after its wheel).
_ORDER = (
    "baseline", "crrel", "crrel_fit", "richmond_measured_rut", "van_es",
    "wheel_wong_pit_predicted", "tire_wong_pit_predicted", "wheel_bekker", "bekker",
    "wheel_wong", "tire_wong", "wheel_wong_pit", "tire_wong_pit",
)  # fmt: skip


def _empirical_models(w_n: float, b: float) -> list[ValidationModel]:
    """The models of chapter 2 and CRREL's, and the baseline, at wheel load w_n [N] and
    tyre width b [m]."""
    from .._empirical.crrel import crrel_contact_arc, crrel_wheel
    from .._empirical.models import (
        bekker_rolling_resistance,
        bekker_wheel_sinkage,
        richmond_resistance,
        van_es_compaction_resistance,
    )
    from .._terrain.bekker import BekkerSoil

    lab = BekkerSoil.thesis_lab_snow()
    # Van Es's sigma_i from CRREL's rho_f = 500 kg/m^3 reached under the CIV's 103 kPa
    # with lambda = 1: sigma_i = p exp(lambda (rho_i / rho_f - 1)^2) (the compaction law
    # of `van_es_compaction_resistance`).
    sigma_i = CIV_INFLATION * math.exp((ICE_DENSITY / CIV_FINAL_DENSITY - 1) ** 2)

    def baseline(rows, grid):
        # never called: `validate` predicts each held-out row by the mean of the others.
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
        z = np.asarray(bekker_wheel_sinkage(w_n, d, b, lab.k_c, lab.k_phi, lab.n))
        r = np.asarray(bekker_rolling_resistance(w_n, d, b, lab.k_c, lab.k_phi, lab.n))
        shape = (len(rows["row"]), 1)
        return np.broadcast_to(z, shape), np.broadcast_to(r / w_n, shape)

    def van_es(rows, grid):
        h = rows["snow_depth_m"][:, None]
        rho0 = rows["density_kg_m3"][:, None]
        d_c = van_es_compaction_resistance(b, h, rho0, CIV_FINAL_DENSITY, sigma_i)
        return None, np.asarray(d_c) / w_n

    return [
        ValidationModel(
            "baseline",
            "baseline: mean of the training rows",
            "-",
            baseline,
            note="predicts every held-out row by the mean of the rows it was not held out with",
        ),
        ValidationModel(
            "crrel",
            "CRREL shallow snow (rho_f = 500 kg/m^3)",
            "CRREL 95-7 eq. 1 (z = h(1 - rho0/rho_f)) + eq. 4 (= thesis 2.23) on the "
            "arc a = r arccos(1 - z/r)",
            crrel_fixed,
            fixed="rho_f = 500 kg/m^3 (CRREL 95-7, its value for the CIV's tyres)",
        ),
        ValidationModel(
            "crrel_fit",
            "CRREL shallow snow, rho_f calibrated",
            "as above",
            crrel_fitted,
            grid=np.linspace(FINAL_DENSITY.lower, FINAL_DENSITY.upper, 151),
            fit_target="sinkage",
            parameter="rho_f [kg/m^3]",
            bounds=(FINAL_DENSITY,),
        ),
        ValidationModel(
            "richmond_measured_rut",
            "Richmond (2.23) on the measured rut",
            "R = 21.313 (rho0 w a)^1.1918, a = r arccos(1 - z_measured/r)",
            richmond_measured,
            fixed="Richmond's coefficients (CRREL 95-7 eq. 4)",
            row_inputs="the measured sinkage of each row (a quantity of the table itself)",
        ),
        ValidationModel(
            "van_es",
            "Van Es (2.26), D_c only",
            "D_c with rho_f = 500 kg/m^3, lambda = 1",
            van_es,
            fixed=f"sigma_i = {sigma_i / 1e3:.0f} kPa: the compaction law p = sigma_i "
            "exp(-lambda (rho_i/rho - 1)^2) reaching CRREL's rho_f = 500 kg/m^3 under the "
            "CIV's 103 kPa, lambda = 1 (the thesis's default); D_r = D_d = 0",
        ),
        ValidationModel(
            "bekker",
            "Bekker closed form (2.24/2.25), the thesis's lab snow",
            "z0 and R_c of (2.25)",
            bekker_closed,
            fixed="the lab snow of the row above",
        ),
    ]


def _wheel_models(w_n: float, b: float) -> list[ValidationModel]:
    """The chapter-4 wheel and the deflecting tyre on each snow of the comparison, at wheel
    load w_n [N] and tyre width b [m]."""

    def wheel_model(*args, note="", fixed="", compare_to=None, **kwargs):
        # the chapter-4 wheel at this load and width, with the table's texts
        model = wheel_validation_model(*args, wheel_load=w_n, tyre_width=b, **kwargs)
        return dataclasses.replace(model, note=note, fixed=fixed, compare_to=compare_to)

    table41 = "c = 0.2165 p_w, tan phi = 0.0787, K = D/73.6 (Table 4.1)"
    civ = "p_i = 103 kPa (CRREL 95-7 Table 2), p_c = 0 and section height 0.75 b (assumed)"
    plate_snow = (
        f"p_w = {PLATE_RULE_P_W / 1e3:.2f} kPa (Wong's plate rule on the thesis's Table 2.1), "
        f"z_w = h (1 - rho0 / 500) (CRREL 95-7 eq. 1, rho_f for the CIV), {table41}"
    )
    return [
        wheel_model(
            "wheel_wong_pit_predicted",
            "chapter-4 wheel, Wong snow from depth and density",
            _predicted_pit_terrain,
            None,
            "",
            fixed=plate_snow,
        ),
        wheel_model(
            "tire_wong_pit_predicted",
            "deflecting tyre (103 kPa), Wong snow from depth and density",
            _predicted_pit_terrain,
            None,
            "",
            make_wheel=_civ_tire,
            fixed=f"{civ}; the snow of the row above",
            compare_to="wheel_wong_pit_predicted",
        ),
        wheel_model(
            "wheel_bekker",
            "chapter-4 wheel, Bekker snow (the thesis's lab snow)",
            _bekker_lab_snow,
            None,
            "",
            fixed="Shoop's 200 kg/m^3 laboratory snow as the thesis fits it (section 2.1.1): "
            "n 1.07, k_c 3.43 kN/m^(n+1), k_phi 218.8 kN/m^(n+2); unlimited depth",
            note="at 6.8 kN the wheel sinks past the 85-degree limit of the rim's geometry on "
            "this snow (the closed form below: 0.23 m, deeper than every row's snow)",
        ),
        wheel_model(
            "wheel_wong",
            "chapter-4 wheel, Wong snow, z_w = snow depth",
            _wong_terrain,
            P_W_GRID,
            "p_w [Pa]",
            fixed=table41,
            bounds=(WONG_P_W,),
        ),
        wheel_model(
            "tire_wong",
            "deflecting tyre (103 kPa), Wong snow, z_w = snow depth",
            _wong_terrain,
            P_W_GRID,
            "p_w [Pa]",
            make_wheel=_civ_tire,
            fixed=f"{civ}; {table41}",
            bounds=(WONG_P_W,),
            compare_to="wheel_wong",
        ),
        wheel_model(
            "wheel_wong_pit",
            "chapter-4 wheel, Wong snow from depth and density, 2 parameters",
            _wong_pit_terrain,
            PIT_GRID,
            "p_w [Pa], rho_f [kg/m^3]",
            fit_target="both",
            fixed=f"z_w = h (1 - rho0 / rho_f) (CRREL 95-7 eq. 1); {table41}",
            bounds=(WONG_P_W, FINAL_DENSITY),
        ),
        wheel_model(
            "tire_wong_pit",
            "deflecting tyre (103 kPa), Wong snow from depth and density, 2 parameters",
            _wong_pit_terrain,
            PIT_GRID,
            "p_w [Pa], rho_f [kg/m^3]",
            make_wheel=_civ_tire,
            fit_target="both",
            fixed=f"{civ}; the snow of the row above",
            bounds=(WONG_P_W, FINAL_DENSITY),
            compare_to="wheel_wong_pit",
        ),
    ]


def validation_models(
    *, wheel_load: float = DEFAULT_WHEEL_LOAD, tyre_width: float = DEFAULT_TYRE_WIDTH
) -> list[ValidationModel]:
    """The models compared by [`snowjax.validate`][] (see the module docstring), in the
    order of its table."""
    models = _empirical_models(wheel_load, tyre_width) + _wheel_models(wheel_load, tyre_width)
    return sorted(models, key=lambda m: _ORDER.index(m.key))
