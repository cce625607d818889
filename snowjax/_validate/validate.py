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

import numpy as np

from .models import (  # the models live there; their public names are re-exported here
    DEFAULT_TYRE_WIDTH,
    DEFAULT_WHEEL_LOAD,
    ValidationModel,
    validation_models,
    wheel_validation_model,
)

__all__ = [
    "shoop_2001_table11",
    "crrel_95_1_examples",
    "ValidationModel",
    "ValidationResult",
    "validation_models",
    "wheel_validation_model",
    "validate",
]

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
