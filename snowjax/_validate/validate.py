"""Validation against measured snow data: `snowjax validate`.

Data (package data, `snowjax/data/`):

- `shoop_2001_table11.csv`: Shoop (2001), ERDC/CRREL TR-01-16, Table 11, measured sinkage
  and snow resistance coefficient of the CRREL Instrumented Vehicle's leading Michelin XCH4
  tyres (radius 0.38 m) in shallow natural snow (26 legible rows of known radius, 2 more of
  uncertain radius, excluded by default).
- `crrel_95_1_examples.csv`: the CRM-1 sample runs of CRREL 95-1, Table A5 (M113) — model
  outputs, used as worked examples of the CRREL model, not as measurements.

Every model predicts the sinkage [m] and/or the resistance coefficient R/W [-] of each
row of Table 11.  A **prediction** takes every parameter from the literature or from other
data (its source named), nothing from the rows it is scored on.  A **calibration** chooses
its parameters on the rows (grid search, least squares), each within a range taken from a
cited source (`ParameterBound`), and is scored by **cross-validation that refits it per fold**:
the rows are grouped by their snow (Table 11's only record of which snow a row was
measured in is its density: 160, 170 and 220 kg/m^3), and each group is predicted with the
parameters chosen on the other groups (`groups="row"`: leave-one-out instead).  The
baseline predicts each held-out row by the mean of the training rows; the skill of a model
is 1 - MSE / MSE_baseline on the same held-out rows (0: no better than the mean).  A
calibration whose choice stops at the end of its range in any fold is flagged; for a tyre,
the report gives its own contribution, tyre minus rigid rim at the parameters chosen.

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
# cross-validation
# ----------------------------------------------------------------------------------------


# Error scales of a model fitted to both quantities (`fit_target="both"`): the sum of
# squared errors in units of sinkage 10 mm and R/W 0.025 (the scales of the measured
# spread), so that neither quantity dominates by its units.
BOTH_SCALES = {"sinkage": 0.010, "coefficient": 0.025}


def snow_groups(rows: dict[str, np.ndarray], groups: str = "snow") -> np.ndarray:
    """The cross-validation fold of each row: its snow, identified by its density
    (`groups="snow"`), or the row itself (`"row"`: leave-one-out)."""
    if groups == "snow":
        return np.unique(rows["density_kg_m3"], return_inverse=True)[1]
    if groups == "row":
        return np.arange(len(rows["row"]))
    raise ValueError(f"groups must be 'snow' or 'row', got {groups!r}")


def _fold_choice(sq: np.ndarray, folds: np.ndarray) -> np.ndarray:
    """The grid index chosen for each row: least summed `sq` (n_rows, grid) over the
    rows of the other folds.  A grid point where any training row has no (finite)
    prediction is never chosen."""
    finite = np.isfinite(sq)
    sq0 = np.where(finite, sq, 0.0)
    chosen = np.empty(len(sq), dtype=int)
    for fold in np.unique(folds):
        train = folds != fold
        total = np.where((~finite[train]).any(axis=0), np.inf, sq0[train].sum(axis=0))
        chosen[folds == fold] = int(np.argmin(total))
    return chosen


def _fold_mean(measured: np.ndarray, folds: np.ndarray) -> np.ndarray:
    """Each row predicted by the mean of the rows of the other folds."""
    out = np.empty_like(measured, dtype=float)
    for fold in np.unique(folds):
        out[folds == fold] = measured[folds != fold].mean()
    return out


def _cross_validate(model, table, measured, folds):
    """(held-out predictions by quantity, grid index chosen per row or None)."""
    if model.grid is None:
        return {
            q: None if t is None else np.asarray(t, float)[:, 0] for q, t in table.items()
        }, None
    assert model.fit_target is not None  # a calibration names its target
    targets = tuple(BOTH_SCALES) if model.fit_target == "both" else (model.fit_target,)
    scales = BOTH_SCALES if model.fit_target == "both" else {}
    sq = sum(
        ((np.asarray(table[q], float) - measured[q][:, None]) / scales.get(q, 1.0)) ** 2
        for q in targets
    )
    chosen = _fold_choice(np.asarray(sq), folds)
    rows = np.arange(len(chosen))
    pred = {q: None if t is None else np.asarray(t, float)[rows, chosen] for q, t in table.items()}
    return pred, chosen


def _at_bounds(model, chosen) -> list[str]:
    """The bounds a calibration's choice reached in some fold ("rho_f [kg/m^3] = 650
    (upper)")."""
    if chosen is None:
        return []
    columns = model.grid.reshape(len(model.grid), -1)
    hit = []
    for k, bound in enumerate(model.bounds):
        values = columns[chosen, k]
        for end, side in ((bound.lower, "lower"), (bound.upper, "upper")):
            if np.any(np.isclose(values, end, rtol=1e-9)):
                hit.append(f"{bound.name} = {end:.4g} ({side})")
    return hit


def _metrics(model, pred, chosen, measured, baseline, contribution) -> list[dict]:
    """One row of metrics per quantity the model predicts."""
    out = []
    columns = None if chosen is None else model.grid.reshape(len(model.grid), -1)[chosen]
    for q, p in pred.items():
        if p is None:
            continue
        err = p - measured[q]
        finite = np.isfinite(err)
        base_err = baseline[q] - measured[q]
        mse = float(np.mean(err[finite] ** 2)) if finite.any() else math.nan
        mse_base = float(np.mean(base_err[finite] ** 2)) if finite.any() else math.nan
        out.append(
            {
                "model": model.key,
                "label": model.label,
                "kind": model.kind,
                "quantity": q,
                "n": int(finite.sum()),
                "n_rows": len(err),
                "rms": math.sqrt(mse),
                "worst": float(np.max(np.abs(err[finite]))) if finite.any() else math.nan,
                "bias": float(np.mean(err[finite])) if finite.any() else math.nan,
                "skill": 1 - mse / mse_base if mse_base > 0 else math.nan,
                "parameter": model.parameter,
                "chosen": None if columns is None else sorted({tuple(c) for c in columns}),
                "at_bounds": _at_bounds(model, chosen),
                "tyre_minus_rim": None if contribution is None else contribution.get(q),
            }
        )
    return out


def _contribution(model, table, chosen, tables) -> dict | None:
    """Tyre minus rim (`model.compare_to`) at the parameters chosen for each row: (mean,
    largest magnitude) per quantity."""
    rim = tables.get(model.compare_to) if model.compare_to else None
    if rim is None:
        return None
    rows = np.arange(len(table["sinkage"]))
    index = np.zeros(len(rows), int) if chosen is None else chosen
    out = {}
    for q in ("sinkage", "coefficient"):
        if table[q] is None or rim[q] is None:
            continue
        diff = np.asarray(table[q], float)[rows, index] - np.asarray(rim[q], float)[rows, index]
        diff = diff[np.isfinite(diff)]
        out[q] = (float(diff.mean()), float(np.max(np.abs(diff)))) if diff.size else None
    return out


@dataclasses.dataclass
class ValidationResult:
    """What [`snowjax.validate`][] measured.

    - `predictions`: {model key: {"sinkage": array | None, "coefficient": array | None}},
      the held-out predictions, one per row of `data`.
    - `metrics`: list of dicts (model, kind, quantity, n, rms, worst, bias, skill against
      the baseline, parameter, chosen values, at_bounds, tyre_minus_rim).
    - `examples`: the CRREL 95-1 worked-example comparison (dict of arrays).
    - `data`: the Table 11 rows used; `folds`: each row's cross-validation fold.
      `files`: written paths.  `skipped`: {key: reason}.  `models`: the models compared.
    """

    predictions: dict
    metrics: list
    examples: dict
    data: dict
    files: list
    skipped: dict
    models: list
    folds: np.ndarray | None = None


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
    groups: str = "snow",
    progress: bool = False,
) -> ValidationResult:
    """Compare every model with Shoop (2001) Table 11 (predictions, and calibrations
    scored by cross-validation), and the CRREL model with the CRM-1 examples of CRREL
    95-1; write the report.

    **Arguments:**

    - `out_dir`: directory for `report.md`, `predictions.csv`, `metrics.csv`,
      `crrel_95_1_examples.csv`, `predicted_vs_measured.png` (None: write nothing).
    - `include_uncertain`: also use the two rows of uncertain tyre radius.
    - `wheel_load` [N], `tyre_width` [m]: not given by Table 11 (see the module docstring).
    - `models`: the models to compare (default [`snowjax.validation_models`][]); add your
      own, e.g. [`snowjax.wheel_validation_model`][] with another terrain.
    - `groups`: the folds of the cross-validation, `"snow"` (rows of one snow held out
      together) or `"row"` (leave-one-out).
    - `progress`: show a rich progress bar.

    **Returns:** a [`snowjax.ValidationResult`][].
    """
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    rows = shoop_2001_table11(include_uncertain)
    folds = snow_groups(rows, groups)
    if models is None:
        models = validation_models(wheel_load=wheel_load, tyre_width=tyre_width)
    measured = {"sinkage": rows["sinkage_m"], "coefficient": rows["resistance_coefficient"]}
    baseline = {q: _fold_mean(m, folds) for q, m in measured.items()}
    predictions, metrics, skipped, tables = {}, [], {}, {}
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
                pred, chosen, contribution = dict(baseline), None, None
            else:
                try:
                    z, mu = model.evaluate(
                        rows, np.asarray([0.0]) if model.grid is None else model.grid
                    )
                except Exception as err:  # a terrain the wheel solver does not support
                    skipped[model.key] = f"{type(err).__name__}: {err}"
                    bar.advance(task)
                    continue
                tables[model.key] = table = {"sinkage": z, "coefficient": mu}
                pred, chosen = _cross_validate(model, table, measured, folds)
                contribution = _contribution(model, table, chosen, tables)
            predictions[model.key] = pred
            metrics += _metrics(model, pred, chosen, measured, baseline, contribution)
            bar.advance(task)
        bar.update(task, description="validate: CRREL 95-1 examples")
        examples = _crrel_examples_check()
        bar.advance(task)
    result = ValidationResult(predictions, metrics, examples, rows, [], skipped, models, folds)
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
        ax.set_ylabel(f"model {q} (held out) [{unit}]")
        ax.grid(True, alpha=0.3)
        ax.set_title("Sinkage" if q == "sinkage" else "Resistance coefficient R/W")
    axes[1].legend(fontsize=7, loc="upper left")
    fig.suptitle(
        "Shoop (2001) Table 11: predictions, and calibrations on held-out snows", fontsize=10
    )
    fig.savefig(path, dpi=110)
    return path


def _parameters(model, by) -> str:
    """The 'parameters' cell of a model: fixed, or fitted (to what, the values chosen per
    fold, a bound reached)."""
    if model.key == "baseline":
        return "mean of the training rows"
    if model.grid is None:
        cell = "none fitted"
        return cell + ("; uses " + model.row_inputs if model.row_inputs else "")
    target = "sinkage and R/W" if model.fit_target == "both" else model.fit_target
    r = next(iter(by.values()))
    values = "; ".join(", ".join(_fmt(v, 3) for v in c) for c in (r["chosen"] or []))
    cell = f"{model.parameter} fitted to {target}: {values}"
    if r["at_bounds"]:
        cell += " — **at its bound** (" + ", ".join(r["at_bounds"]) + ")"
    return cell


def _rms_cell(r) -> str:
    """RMS, and the rows it covers where the model has no value for some (no
    equilibrium: the wheel would sink past 85 degrees)."""
    if r is None:
        return "-"
    if r["n"] < r["n_rows"]:
        return f"{_fmt(r['rms'], 3)} ({r['n']} of {r['n_rows']} rows)"
    return _fmt(r["rms"], 3)


def metrics_table_markdown(metrics: list, models: list) -> str:
    """The table of [`snowjax.validate`][] as Markdown: per model its kind, its fitted
    parameters, RMS and skill of sinkage and R/W and the R/W bias."""
    by_model: dict = {}
    for r in metrics:
        by_model.setdefault(r["model"], {})[r["quantity"]] = r
    lines = [
        "| model | kind | parameters | sinkage RMS [m] | sinkage skill | R/W RMS [-] | "
        "R/W skill | R/W bias [-] |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for model in models:
        by = by_model.get(model.key)
        if not by:
            continue
        s, c = by.get("sinkage"), by.get("coefficient")
        lines.append(
            f"| {model.label} | {model.kind} | {_parameters(model, by)} | "
            f"{_rms_cell(s)} | {_fmt(s and s['skill'], 2)} | "
            f"{_rms_cell(c)} | {_fmt(c and c['skill'], 2)} | "
            f"{_fmt(c and c['bias'], 2)} |"
        )
    return "\n".join(lines)


def _sources_markdown(models: list, metrics: list) -> str:
    """One bullet per model: what it fixes and where from, what it fits within which
    bounds, and a tyre's own contribution."""
    contribution = {
        (r["model"], r["quantity"]): r["tyre_minus_rim"]
        for r in metrics
        if r["tyre_minus_rim"] is not None
    }
    lines = []
    for model in models:
        parts = [f"**{model.label}** ({model.kind})"]
        if model.fixed:
            parts.append(f"fixed: {model.fixed}")
        for bound in model.bounds:
            parts.append(
                f"fitted: {bound.name} in [{bound.lower:.4g}, {bound.upper:.4g}], {bound.source}"
            )
        if model.row_inputs:
            parts.append(f"takes {model.row_inputs}")
        for q, name in (("sinkage", "sinkage [m]"), ("coefficient", "R/W")):
            value = contribution.get((model.key, q))
            if value is not None:
                parts.append(
                    f"tyre − rim {name} at the parameters chosen: mean {_fmt(value[0], 2)}, "
                    f"largest magnitude {_fmt(value[1], 2)}"
                )
        if model.note:
            parts.append(model.note)
        lines.append("- " + "; ".join(parts) + ".")
    return "\n".join(lines)


def _write(out: pathlib.Path, result: ValidationResult, wheel_load, tyre_width):
    out.mkdir(parents=True, exist_ok=True)
    rows = result.data
    files = []
    cols = {
        "row": rows["row"],
        "fold": result.folds,
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
    mkeys = ["model", "kind", "quantity", "n", "n_rows", "rms", "worst", "bias", "skill"]
    lines = [",".join([*mkeys, "chosen", "at_bounds"])]
    for r in result.metrics:
        chosen = (
            ""
            if r["chosen"] is None
            else " ".join("/".join(f"{v:.6g}" for v in c) for c in r["chosen"])
        )
        cells = [str(r[k]) if isinstance(r[k], (str, int)) else _fmt(r[k], 6) for k in mkeys]
        lines.append(",".join([*cells, chosen, " ".join(r["at_bounds"]).replace(",", ";")]))
    (out / "metrics.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    files.append(out / "metrics.csv")
    files.append(_write_csv(out / "crrel_95_1_examples.csv", result.examples))
    files.append(_figure(result, out / "predicted_vs_measured.png"))
    (out / "report.md").write_text(_report(result, wheel_load, tyre_width), encoding="utf-8")
    files.append(out / "report.md")
    return files


def _report(result: ValidationResult, wheel_load, tyre_width) -> str:
    rows, ex = result.data, result.examples
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
    folds = result.folds if result.folds is not None else np.zeros(len(depth), int)
    n_folds = len(np.unique(folds))
    scheme = (
        f"{n_folds} snows, grouped by density ("
        + ", ".join(f"{d:.0f} kg/m³: {int(np.sum(density == d))} rows" for d in np.unique(density))
        + ")"
        if n_folds < len(depth)
        else "leave-one-out"
    )
    return f"""# snowjax validate

## Data

**Shoop (2001), ERDC/CRREL TR-01-16, Table 11** — measured sinkage and snow resistance
coefficient R/W of leading Michelin XCH4 tyres (radius 0.38 m) of the CRREL Instrumented
Vehicle in shallow natural snow (Houghton, Michigan; Blaisdell et al. 1990, Richmond 1995).
{len(rows["row"])} rows used (snow depth {depth.min():.2f}–{depth.max():.2f} m,
density {density.min():.0f}–{density.max():.0f} kg/m³). Wheel load
{wheel_load:.0f} N and tyre width {tyre_width:.3f} m are not given by Table 11 (load: CRREL 95-7
Table 2, an interpretation; width: an assumption) — they scale every modelled R/W.
Source, units and every interpretation: `snowjax/data/shoop_2001_table11.csv`.

The measured ruts imply a compacted density rho0 h / (h − z) of {np.median(implied):.0f} kg/m³
(median; range {implied.min():.0f}–{implied.max():.0f}), above CRREL's 500–650 kg/m³ and in
{int(np.sum(implied > 917))} rows above ice (917 kg/m³): the ruts are deeper than vertical
compaction of the snow column explains. Mechanisms no model here has: snow pushed aside
and out of the rut, sidewall contact.

## Method

A **prediction** takes every parameter from the literature or other data (named below),
nothing from the rows it is scored on. A **calibration** chooses its parameters on the
rows, each within a range from a cited source, and is scored by **cross-validation with the
fit repeated per fold**: {scheme}; each fold is predicted with the parameters chosen on the
others. The baseline predicts each held-out row by the mean of the training rows. **Skill**
= 1 − MSE / MSE_baseline on the held-out rows: 0 is no better than the mean, below 0
worse. A choice at the end of its range in any fold is flagged.{skipped}

## Results

{metrics_table_markdown(result.metrics, result.models)}

![models vs measured](predicted_vs_measured.png)

### Parameters and their sources

{_sources_markdown(result.models, result.metrics)}

Numbers: `metrics.csv` (also the worst error and the values chosen per fold),
`predictions.csv` (every held-out value, with each row's fold).

## CRREL 95-1 worked examples (CRM-1, M113)

Model output, not measurements. snowjax's rut depth is CRREL 95-7 eq. 1 with rho_f from
the CRREL pressure table (M113 nominal ground pressure {ex["ground_pressure_pa"][0] / 1e3:.0f} kPa
→ rho_f = {ex["final_density_kg_m3"][0]:.0f} kg/m³); drawbar = T − R − W sin(slope) from the
printed traction T and resistance R (W = 23,401 lb = {M113_WEIGHT_LB * LB_TO_N:.1f} N). The gross
traction and resistance equations themselves are not in the stored copy of the report.

{chr(10).join(ex_lines)}
"""
