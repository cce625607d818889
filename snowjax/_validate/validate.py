"""Validation against measured snow data: `snowjax validate`.

Data (package data, `snowjax/data/`):

- `shoop_2001_table11.csv`: Shoop (2001), ERDC/CRREL TR-01-16, Table 11, measured sinkage
  and snow resistance coefficient of the CRREL Instrumented Vehicle's leading Michelin XCH4
  tyres (radius 0.38 m) in shallow natural snow (26 legible rows of known radius, 2 more of
  uncertain radius, excluded by default).
- `crrel_95_1_examples.csv`: the CRM-1 sample runs of CRREL 95-1, Table A5 (M113) — model
  outputs, used as worked examples of the CRREL model, not as measurements.

Every model predicts the sinkage [m] and/or the resistance coefficient R/W [-] of each
row of Table 11.  A model with a free parameter is calibrated by **leave-one-out
cross-validation**: for each row, the parameter is chosen (grid search, least squares)
on the other rows, and the row is predicted with it; the errors reported are those
held-out predictions only.  Models without a free parameter are pure predictions.

Table 11 gives neither the wheel load nor the tyre width.  Defaults (arguments of
[`snowjax.validate`][]): wheel load 6,800 N — the first column of CRREL 95-7's Table 2
for the CIV's front tyres at 103 kPa inflation (6,800 front, 5,510 rear), read as the
wheel load in N; the column heading is not legible in the stored copy, so this is an
interpretation — and tyre width 0.235 m, an assumption (the thesis's tyre width; the
XCH4's size on the CIV is not in the stored sources).
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import math
import pathlib
from collections.abc import Callable

import numpy as np

__all__ = [
    "shoop_2001_table11",
    "crrel_95_1_examples",
    "ValidationModel",
    "ValidationResult",
    "validation_models",
    "wheel_validation_model",
    "validate",
]

DEFAULT_WHEEL_LOAD = 6800.0  # [N], CRREL 95-7 Table 2 (interpretation, see module docs)
DEFAULT_TYRE_WIDTH = 0.235  # [m], assumption
CIV_FINAL_DENSITY = 500.0  # [kg/m^3], CRREL 95-7: the value used for the CIV's tyres
CIV_INFLATION = 103e3  # [Pa], CRREL 95-7 Table 2: the CIV's tyres at the lower pressure
CIV_SECTION_RATIO = 0.75  # section height / width [-], an assumption (a 75-series tyre)
M113_WEIGHT_LB = 23401.0  # CRREL 95-1 Appendix A vehicle file
LB_TO_N = 0.45359237 * 9.80665
IN_TO_M = 0.0254


def _read_csv(name: str) -> dict[str, np.ndarray]:
    path = importlib.resources.files("snowjax") / "data" / name
    lines = [
        ln.strip()
        for ln in path.read_text(encoding="utf-8-sig").splitlines()
        if ln.strip() and not ln.lstrip().startswith("#")
    ]
    header = [h.strip() for h in lines[0].split(",")]
    values = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])
    return {h: values[:, k] for k, h in enumerate(header)}


def shoop_2001_table11(include_uncertain: bool = False) -> dict[str, np.ndarray]:
    """Shoop (2001), ERDC/CRREL TR-01-16, Table 11: measured sinkage and resistance in snow.

    Keys (SI): `row`, `snow_depth_m` [m], `sinkage_m` [m], `resistance_coefficient` [-]
    (snow resistance / wheel load), `density_kg_m3` [kg/m^3], `radius_m` [m], `certain`
    (1 = legible and of the stated 0.38 m radius).  See the CSV's header for the source
    and every interpretation.  `include_uncertain=False` drops the two rows of uncertain
    radius (rows 27, 28).
    """
    t = _read_csv("shoop_2001_table11.csv")
    if not include_uncertain:
        keep = t["certain"] == 1
        t = {k: v[keep] for k, v in t.items()}
    return t


def crrel_95_1_examples() -> dict[str, np.ndarray]:
    """CRREL 95-1, Table A5: the five CRM-1 sample runs for the M113 (SI units; see the CSV
    header for the conversions and the two interpretations)."""
    return _read_csv("crrel_95_1_examples.csv")


# ----------------------------------------------------------------------------------------
# models
# ----------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class ValidationModel:
    """A model compared with Table 11.

    `evaluate(rows, grid)` returns `(sinkage, coefficient)`, each of shape
    `(n_rows, len(grid))` (or `None` for a quantity the model does not predict); `grid`
    is the 1-D grid of the calibrated parameter (`None`: nothing to calibrate, shape
    `(n_rows, 1)`).  `fit_target` is the quantity the parameter is fitted to
    (`"sinkage"` or `"coefficient"`).
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
    stored sources)."""
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
        wheel_validation_model(
            "wheel_wong",
            "chapter-4 wheel, Wong snow (z_w = h)",
            _wong_terrain,
            np.geomspace(2e3, 400e3, 81),
            "p_w [Pa]",
            wheel_load=w_n,
            tyre_width=b,
            note="Table 4.1 ratios c/p_w = 0.2165, tan phi = 0.0787, K = D/73.6; p_w fitted",
        ),
        wheel_validation_model(
            "tire_wong",
            "deflecting tyre (103 kPa), Wong snow (z_w = h)",
            _wong_terrain,
            np.geomspace(2e3, 400e3, 81),
            "p_w [Pa]",
            wheel_load=w_n,
            tyre_width=b,
            make_wheel=_civ_tire,
            note="DeflectingTire p_i = 103 kPa (CRREL 95-7 Table 2), p_c = 0 and section "
            "height 0.75 b (assumed); snow as the row above; p_w fitted",
        ),
        wheel_validation_model(
            "wheel_wong_pit",
            "chapter-4 wheel, Wong snow from depth and density, 2 parameters",
            _wong_pit_terrain,
            PIT_GRID,
            "p_w [Pa], rho_f [kg/m^3]",
            wheel_load=w_n,
            tyre_width=b,
            fit_target="both",
            note="z_w = h (1 - rho0 / rho_f) (CRREL 95-7 eq. 1); Table 4.1 ratios; p_w and "
            "rho_f fitted to sinkage and R/W together",
        ),
        wheel_validation_model(
            "tire_wong_pit",
            "deflecting tyre (103 kPa), Wong snow from depth and density, 2 parameters",
            _wong_pit_terrain,
            PIT_GRID,
            "p_w [Pa], rho_f [kg/m^3]",
            wheel_load=w_n,
            tyre_width=b,
            make_wheel=_civ_tire,
            fit_target="both",
            note="the tyre of the row above on the snow of the row above",
        ),
        wheel_validation_model(
            "wheel_bekker",
            "chapter-4 wheel, Bekker snow (unlimited depth)",
            _bekker_terrain,
            np.geomspace(0.1, 100.0, 61),
            "scale of (k_c, k_phi)",
            wheel_load=w_n,
            tyre_width=b,
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


# ----------------------------------------------------------------------------------------
# leave-one-out
# ----------------------------------------------------------------------------------------


# Error scales of a model fitted to both quantities (`fit_target="both"`): the sum of
# squared errors in units of the targets of the tyre issue (sinkage RMS 10 mm, R/W RMS
# 0.025), so that neither quantity dominates by its units.
BOTH_SCALES = {"sinkage": 0.010, "coefficient": 0.025}


def _loo_choice(sq: np.ndarray) -> np.ndarray:
    """The grid index chosen for each held-out row i: least summed `sq` (n_rows, grid)
    over the other rows.  A grid point where any training row has no (finite) prediction
    is never chosen."""
    n, g = sq.shape
    finite = np.isfinite(sq)
    sq0 = np.where(finite, sq, 0.0)
    total, n_bad = sq0.sum(axis=0), (~finite).sum(axis=0)
    chosen = np.empty(n, dtype=int)
    for i in range(n):
        train = np.where(n_bad - ~finite[i] > 0, np.inf, total - sq0[i])
        chosen[i] = int(np.argmin(train)) if g > 1 else 0
    return chosen


def _loo_from_grid(pred: np.ndarray, measured: np.ndarray):
    """Held-out prediction of each row and the parameter index chosen without it."""
    chosen = _loo_choice((pred - measured[:, None]) ** 2)
    return pred[np.arange(len(pred)), chosen], chosen


def _loo_mean(measured: np.ndarray) -> np.ndarray:
    n = len(measured)
    return (measured.sum() - measured) / (n - 1)


@dataclasses.dataclass
class ValidationResult:
    """What [`snowjax.validate`][] measured.

    - `predictions`: {model key: {"sinkage": array | None, "coefficient": array | None}},
      the held-out predictions, one per row of `data`.
    - `metrics`: list of dicts (model, quantity, n, rms, worst, bias, parameter, chosen).
    - `examples`: the CRREL 95-1 worked-example comparison (dict of arrays).
    - `data`: the Table 11 rows used.  `files`: written paths.  `skipped`: {key: reason}.
    """

    predictions: dict
    metrics: list
    examples: dict
    data: dict
    files: list
    skipped: dict
    models: list


def _crrel_examples_check() -> dict[str, np.ndarray]:
    from .._empirical.crrel import crrel_drawbar, crrel_final_density, crrel_sinkage

    ex = crrel_95_1_examples()
    weight = M113_WEIGHT_LB * LB_TO_N
    # nominal ground pressure of the M113's two tracks (15 in x 105 in each): 51 kPa;
    # CRM-1 uses the peak element pressure (not in the stored copy): any value <= 210 kPa
    # gives the same rho_f.
    pressure = weight / (2 * (15.0 * IN_TO_M) * (105.0 * IN_TO_M))
    rho_f = np.asarray(crrel_final_density(pressure))
    undisturbed = ex["snow_type"] == 7
    rho0 = np.where(undisturbed, ex["density_kg_m3"], 200.0)
    rut = np.where(undisturbed, np.asarray(crrel_sinkage(ex["snow_depth_m"], rho0, rho_f)), 0.0)
    level_resistance = np.where(
        ex["slope_rad"] > 0,
        ex["resistance_n"] - weight * np.sin(ex["slope_rad"]),
        ex["resistance_n"],
    )
    pull, coeff = crrel_drawbar(ex["gross_traction_n"], level_resistance, weight, ex["slope_rad"])
    return {
        "example": ex["example"],
        "snow_depth_m": ex["snow_depth_m"],
        "snow_type": ex["snow_type"],
        "rut_depth_report_m": ex["rut_depth_m"],
        "rut_depth_snowjax_m": rut,
        "drawbar_report_n": ex["drawbar_n"],
        "drawbar_snowjax_n": np.asarray(pull),
        "drawbar_coefficient_report": ex["drawbar_coefficient"],
        "drawbar_coefficient_snowjax": np.asarray(coeff),
        "final_density_kg_m3": np.full(len(ex["example"]), float(rho_f)),
        "ground_pressure_pa": np.full(len(ex["example"]), pressure),
    }


def validate(
    out_dir: str | pathlib.Path | None = None,
    *,
    include_uncertain: bool = False,
    wheel_load: float = DEFAULT_WHEEL_LOAD,
    tyre_width: float = DEFAULT_TYRE_WIDTH,
    models: list[ValidationModel] | None = None,
    progress: bool = False,
) -> ValidationResult:
    """Compare every model with Shoop (2001) Table 11 by leave-one-out cross-validation,
    and the CRREL model with the CRM-1 examples of CRREL 95-1; write the report.

    **Arguments:**

    - `out_dir`: directory for `report.md`, `predictions.csv`, `metrics.csv`,
      `crrel_95_1_examples.csv`, `predicted_vs_measured.png` (None: write nothing).
    - `include_uncertain`: also use the two rows of uncertain tyre radius.
    - `wheel_load` [N], `tyre_width` [m]: not given by Table 11 (see the module docstring).
    - `models`: the models to compare (default [`snowjax.validation_models`][]); add your
      own, e.g. [`snowjax.wheel_validation_model`][] with another terrain.
    - `progress`: show a rich progress bar.

    **Returns:** a [`snowjax.ValidationResult`][].
    """
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    rows = shoop_2001_table11(include_uncertain)
    models = (
        validation_models(wheel_load=wheel_load, tyre_width=tyre_width)
        if models is None
        else models
    )
    measured = {"sinkage": rows["sinkage_m"], "coefficient": rows["resistance_coefficient"]}
    predictions, metrics, skipped = {}, [], {}
    columns = (
        TextColumn("[progress.description]{task.description}"),
        BarColumn(),
        TimeElapsedColumn(),
    )
    with Progress(*columns, disable=not progress) as bar:
        task = bar.add_task("validate", total=len(models) + 1)
        for model in models:
            bar.update(task, description=f"validate: {model.key}")
            if model.key == "baseline":
                pred = {q: _loo_mean(m) for q, m in measured.items()}
                chosen = None
            else:
                try:
                    grid = np.asarray([0.0]) if model.grid is None else model.grid
                    z, mu = model.evaluate(rows, grid)
                except Exception as err:  # a terrain the wheel solver does not support
                    skipped[model.key] = f"{type(err).__name__}: {err}"
                    bar.advance(task)
                    continue
                table = {"sinkage": z, "coefficient": mu}
                pred, chosen = {}, None
                if model.grid is not None:
                    assert model.fit_target is not None  # a grid model names its target
                    targets = (
                        tuple(BOTH_SCALES) if model.fit_target == "both" else (model.fit_target,)
                    )
                    scales = BOTH_SCALES if model.fit_target == "both" else {}
                    sq = sum(
                        (
                            (np.asarray(table[q], dtype=float) - measured[q][:, None])
                            / scales.get(q, 1.0)
                        )
                        ** 2
                        for q in targets
                    )
                    chosen = _loo_choice(np.asarray(sq))
                for q, t in table.items():
                    if t is None:
                        pred[q] = None
                        continue
                    t = np.asarray(t, dtype=float)
                    pred[q] = t[:, 0] if chosen is None else t[np.arange(len(t)), chosen]
            predictions[model.key] = pred
            for q, p in pred.items():
                if p is None:
                    continue
                err = p - measured[q]
                finite = np.isfinite(err)
                params = None if chosen is None or model.grid is None else model.grid[chosen]
                columns = None if params is None else params.reshape(len(params), -1)
                grid_columns = (
                    None if model.grid is None else model.grid.reshape(len(model.grid), -1)
                )
                metrics.append(
                    {
                        "model": model.key,
                        "label": model.label,
                        "quantity": q,
                        "n": int(finite.sum()),
                        "n_rows": len(err),
                        "rms": float(np.sqrt(np.mean(err[finite] ** 2)))
                        if finite.any()
                        else math.nan,
                        "worst": float(np.max(np.abs(err[finite]))) if finite.any() else math.nan,
                        "bias": float(np.mean(err[finite])) if finite.any() else math.nan,
                        "parameter": model.parameter,
                        # The first parameter's (the only one for a 1-D grid); every
                        # parameter's median in `chosen_medians`.
                        "chosen_median": None
                        if columns is None
                        else float(np.median(columns[:, 0])),
                        "chosen_min": None if columns is None else float(np.min(columns[:, 0])),
                        "chosen_max": None if columns is None else float(np.max(columns[:, 0])),
                        "chosen_medians": None
                        if columns is None
                        else tuple(float(x) for x in np.median(columns, axis=0)),
                        "at_grid_edge": bool(
                            columns is not None
                            and grid_columns is not None
                            and np.any(
                                (columns == grid_columns.min(axis=0))
                                | (columns == grid_columns.max(axis=0))
                            )
                        ),
                    }
                )
            bar.advance(task)
        bar.update(task, description="validate: CRREL 95-1 examples")
        examples = _crrel_examples_check()
        bar.advance(task)
    result = ValidationResult(
        predictions=predictions,
        metrics=metrics,
        examples=examples,
        data=rows,
        files=[],
        skipped=skipped,
        models=models,
    )
    if out_dir is not None:
        result.files = _write(pathlib.Path(out_dir), result, wheel_load, tyre_width)
    return result


# ----------------------------------------------------------------------------------------
# output
# ----------------------------------------------------------------------------------------


def _fmt(x, digits=4):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return f"{x:.{digits}g}"


def _write_csv(path: pathlib.Path, columns: dict[str, np.ndarray]) -> pathlib.Path:
    keys = list(columns)
    n = len(next(iter(columns.values())))
    lines = [",".join(keys)]
    for i in range(n):
        lines.append(
            ",".join(_fmt(float(columns[k][i]), 8) if columns[k] is not None else "" for k in keys)
        )
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _figure(result: ValidationResult, path: pathlib.Path) -> pathlib.Path:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 5), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 2)
    markers = "os^vD<>pXh*"
    labels = {m.key: m.label for m in result.models}
    for ax, q, unit in ((axes[0], "sinkage", "m"), (axes[1], "coefficient", "-")):
        meas = result.data["sinkage_m" if q == "sinkage" else "resistance_coefficient"]
        lo, hi = np.nanmin(meas), np.nanmax(meas)
        for k, (key, pred) in enumerate(result.predictions.items()):
            p = pred.get(q)
            if p is None:
                continue
            ax.plot(meas, p, markers[k % len(markers)], ms=5, alpha=0.75, label=labels[key])
            finite = p[np.isfinite(p)]
            if finite.size:
                lo, hi = min(lo, finite.min()), max(hi, finite.max())
        ax.plot([lo, hi], [lo, hi], "k--", lw=1, label="predicted = measured")
        ax.set_xlabel(f"measured {q} [{unit}]")
        ax.set_ylabel(f"predicted {q} (held out) [{unit}]")
        ax.grid(True, alpha=0.3)
        ax.set_title("Sinkage" if q == "sinkage" else "Resistance coefficient R/W")
    axes[1].legend(fontsize=7, loc="upper left")
    fig.suptitle("Shoop (2001) Table 11, leave-one-out predictions", fontsize=10)
    fig.savefig(path, dpi=110)
    return path


def metrics_table_markdown(metrics: list, models: list) -> str:
    """The RMS / worst-error table of [`snowjax.validate`][] as Markdown."""
    labels = {m.key: m.label for m in models}
    calib = {
        m.key: (
            f"{m.parameter} (LOO on "
            + ("sinkage and R/W" if m.fit_target == "both" else m.fit_target)
            + ")"
            if m.grid is not None
            else "none"
        )
        for m in models
    }
    by = {(r["model"], r["quantity"]): r for r in metrics}
    lines = [
        "| model | calibrated | sinkage RMS [m] | sinkage worst [m] | "
        "R/W RMS [-] | R/W worst [-] | R/W bias [-] |",
        "|---|---|---|---|---|---|---|",
    ]
    for key in dict.fromkeys(r["model"] for r in metrics):
        s, c = by.get((key, "sinkage")), by.get((key, "coefficient"))
        cal = calib.get(key, "")
        for r in (s, c):
            if r and r["chosen_median"] is not None:
                medians = r.get("chosen_medians") or (r["chosen_median"],)
                cal += f"; median {', '.join(_fmt(x, 3) for x in medians)}"
                if r["at_grid_edge"]:
                    cal += " (grid edge)"
                break
        if key == "baseline":
            cal = "mean of the other rows"
        lines.append(
            f"| {labels.get(key, key)} | {cal} | {_fmt(s and s['rms'], 3)} | "
            f"{_fmt(s and s['worst'], 3)} | {_fmt(c and c['rms'], 3)} | "
            f"{_fmt(c and c['worst'], 3)} | {_fmt(c and c['bias'], 2)} |"
        )
    return "\n".join(lines)


def _write(out: pathlib.Path, result: ValidationResult, wheel_load, tyre_width):
    out.mkdir(parents=True, exist_ok=True)
    rows = result.data
    files = []
    cols = {
        "row": rows["row"],
        "snow_depth_m": rows["snow_depth_m"],
        "density_kg_m3": rows["density_kg_m3"],
        "sinkage_measured_m": rows["sinkage_m"],
        "coefficient_measured": rows["resistance_coefficient"],
    }
    for key, pred in result.predictions.items():
        for q, p in pred.items():
            if p is not None:
                cols[f"{q}_{key}"] = p
    files.append(_write_csv(out / "predictions.csv", cols))
    mkeys = [
        "model",
        "quantity",
        "n",
        "n_rows",
        "rms",
        "worst",
        "bias",
        "chosen_median",
        "chosen_min",
        "chosen_max",
    ]
    lines = [",".join(mkeys)] + [
        ",".join(str(r[k]) if isinstance(r[k], (str, int)) else _fmt(r[k], 6) for k in mkeys)
        for r in result.metrics
    ]
    (out / "metrics.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    files.append(out / "metrics.csv")
    files.append(_write_csv(out / "crrel_95_1_examples.csv", result.examples))
    files.append(_figure(result, out / "predicted_vs_measured.png"))

    ex = result.examples
    ex_lines = [
        "| example | snow | rut depth CRM-1 [cm] | snowjax [cm] | drawbar CRM-1 [N] | "
        "snowjax [N] | coefficient CRM-1 | snowjax |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for i in range(len(ex["example"])):
        ex_lines.append(
            f"| {int(ex['example'][i])} | {ex['snow_depth_m'][i] * 100:.0f} cm, "
            f"{'undisturbed' if ex['snow_type'][i] == 7 else 'disturbed'} | "
            f"{ex['rut_depth_report_m'][i] * 100:.1f} | {ex['rut_depth_snowjax_m'][i] * 100:.1f}"
            f" | {ex['drawbar_report_n'][i]:.1f} | {ex['drawbar_snowjax_n'][i]:.1f} | "
            f"{ex['drawbar_coefficient_report'][i]:.3f} | "
            f"{ex['drawbar_coefficient_snowjax'][i]:.3f} |"
        )
    implied = (
        rows["density_kg_m3"] * rows["snow_depth_m"] / (rows["snow_depth_m"] - rows["sinkage_m"])
    )
    skipped = "".join(f"\n- `{k}` skipped: {v}" for k, v in result.skipped.items())
    depth, density = rows["snow_depth_m"], rows["density_kg_m3"]
    report = f"""# snowjax validate

## Data

**Shoop (2001), ERDC/CRREL TR-01-16, Table 11** — measured sinkage and snow resistance
coefficient R/W of leading Michelin XCH4 tyres (radius 0.38 m) of the CRREL Instrumented
Vehicle in shallow natural snow (Houghton, Michigan; Blaisdell et al. 1990, Richmond 1995).
{len(rows["row"])} rows used (snow depth {depth.min():.2f}–{depth.max():.2f} m,
density {density.min():.0f}–{density.max():.0f} kg/m³). Wheel load
{wheel_load:.0f} N and tyre width {tyre_width:.3f} m are not given by Table 11 (load: CRREL 95-7
Table 2, an interpretation; width: an assumption) — they scale every predicted R/W.
Source, units and every interpretation: `snowjax/data/shoop_2001_table11.csv`.

Note on the data: the measured ruts imply a compacted density rho0 h / (h − z) of
{np.median(implied):.0f} kg/m³ (median; range {implied.min():.0f}–{implied.max():.0f}), above
CRREL's 500 kg/m³ and in {int(np.sum(implied > 917))} rows above ice (917 kg/m³): the ruts are
deeper than vertical compaction of the snow column alone explains (snow pushed aside, or
the measured sinkage including something else), so every compaction model underpredicts them.

## Method

Each model predicts each row **held out**: a model with a free parameter has it chosen
by leave-one-out cross-validation (least squares over a grid on the other rows), so no
number below is a fit to the row it is scored on. The baseline predicts each row by the
mean of the others: a model that does not beat it explains nothing of the row-to-row
variation.{skipped}

## Results

{metrics_table_markdown(result.metrics, result.models)}

![predicted vs measured](predicted_vs_measured.png)

Numbers: `metrics.csv` (also bias and the range of the parameter chosen per fold),
`predictions.csv` (every held-out prediction).

## CRREL 95-1 worked examples (CRM-1, M113)

Model output, not measurements. snowjax's rut depth is CRREL 95-7 eq. 1 with rho_f from
the CRREL pressure table (M113 nominal ground pressure {ex["ground_pressure_pa"][0] / 1e3:.0f} kPa
→ rho_f = {ex["final_density_kg_m3"][0]:.0f} kg/m³); drawbar = T − R − W sin(slope) from the
printed traction T and resistance R (W = 23,401 lb = {M113_WEIGHT_LB * LB_TO_N:.1f} N). The gross
traction and resistance equations themselves are not in the stored copy of the report.

{chr(10).join(ex_lines)}
"""
    (out / "report.md").write_text(report, encoding="utf-8")
    files.append(out / "report.md")
    return files
