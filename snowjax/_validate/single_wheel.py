"""Measured single-wheel forces under slip angle: calibrate on some slip angles, predict
the others.

Data: the steady-state single-wheel sand tests of `robomechanics/3d-terramechanics`
(Pavlov, Carnegie Mellon University, MIT licence), as CSV files in a folder the user
gives (in this repository's CI: `../shared/data/3d-terramechanics/`; its README describes
the rig, the columns and the conventions).  Two rigid wheels (radius 58 mm, width 50 mm;
one smooth, one with 5 mm grousers) in dry sand, 7 slip angles (0-90 deg) x 9 rim
speeds, with the measured F_x (along the heading), F_y (along the axle, resisting the
side-slip), F_z and sinkage, means of 3 trials.

**Slip.**  The data set's slip ratio is `s = (v_rim - V) / max(v_rim, V)` with V the whole
travel speed, not its component along the heading.  snowjax's slip is the driving slip of
the heading's component (eq. 2.6 with V cos beta): with the rim speed v_rim = omega r_s,

    i = 1 - V cos(beta) / v_rim,

computed from the measured rim and travel speeds of each row (`SingleWheelData.slip`).
It is < -1 (outside `solve_wheel`'s range) where the rim turns slower than half the
heading speed: the locked wheel (v_rim = 0, i = -inf) at every beta, and s = -0.7
(v_rim = 0.3 V) for beta < 53 deg.  Those rows are not used (`in_range`) and are
counted separately.  At beta = 90 deg the heading speed is 0 and i = 1 for every rim
speed: the slip angle is outside `solve_wheel`'s range (|beta| < 90 deg), so those rows
are not used either.

**Wheel.**  The smooth wheel is a `RigidWheel(0.116 m, 0.05 m)`.  The grousered wheel is
modelled as a rigid wheel of the grouser-tip radius (the shearing radius, 63 mm), with the
rim speed scaled to that radius (the rig logs v_rim at 58 mm); its sinkage is compared as
logged (the data README notes that its zero, tips or rim, is not stated).
"""

from __future__ import annotations

import csv
import dataclasses
import math
import pathlib

import numpy as np

from .._fit.wheel import fit_wheel
from .._terrain.bekker import BekkerSoil
from .._wheel.distribution import WongReece
from .._wheel.equilibrium import solve_wheel
from .._wheel.geometry import RigidWheel
from .._wheel.lateral import Lateral
from .._wheel.model import ContactModel

__all__ = [
    "SingleWheelData",
    "SingleWheelStudy",
    "load_single_wheel",
    "single_wheel_study",
    "UPSTREAM_RMS",
]

RIG_RADIUS = 0.058  # [m] radius at which the rig logs the rim speed (run_model.m, line 56)
WHEEL_WIDTH = 0.05  # [m]
SHEARING_RADIUS = {"smooth": 0.058, "grousered": 0.063}  # [m] (set_rover_params.m)
SAND_UNIT_WEIGHT = 1330.0 * 9.80665  # [N/m^3] measured bulk density 1330 kg/m^3 x g

# RMS errors of the upstream 3-D model ("no soil flow" variant) over beta <= 60 deg, fitted
# in-sample to these rows (data README, "Reference: accuracy of the upstream 3-D model";
# run under GNU Octave 7.3): (F_x [N], F_y [N], sinkage [m]).
UPSTREAM_RMS = {"smooth": (5.8, 4.6, 0.0053), "grousered": (5.3, 4.9, 0.0059)}


@dataclasses.dataclass(frozen=True)
class SingleWheelData:
    """Condition means of one wheel (one entry per test condition), SI units.

    - `wheel`: "smooth" or "grousered"; `radius`: model radius r_s [m]; `width` b [m].
    - `slip_angle_deg` [deg], `slip_angle` beta [rad] (commanded).
    - `slip_ratio` [-]: the data set's s (see the module docstring).
    - `rim_speed` v_rim at the model radius [m/s]; `travel_speed` V [m/s].
    - `slip` [-]: snowjax's driving slip i = 1 - V cos(beta) / v_rim (-inf when locked).
    - `fx`, `fy`, `fz` [N], `sinkage` [m]: measured means; `*_std`: their sample standard
      deviation over the 3 trials.
    - `in_range`: rows `solve_wheel` can take (-1 <= i <= 1 and beta < 90 deg).
    """

    wheel: str
    radius: float
    width: float
    slip_angle_deg: np.ndarray
    slip_angle: np.ndarray
    slip_ratio: np.ndarray
    rim_speed: np.ndarray
    travel_speed: np.ndarray
    slip: np.ndarray
    fx: np.ndarray
    fy: np.ndarray
    fz: np.ndarray
    sinkage: np.ndarray
    fx_std: np.ndarray
    fy_std: np.ndarray
    sinkage_std: np.ndarray
    in_range: np.ndarray

    def rows(self, angles_deg) -> np.ndarray:
        """Mask of the in-range rows whose slip angle is one of `angles_deg`."""
        return self.in_range & np.isin(np.round(self.slip_angle_deg), list(angles_deg))


COLUMNS = ("slip_ratio", "slip_angle_deg", "slip_angle_rad", "rim_speed_m_s",
           "travel_speed_m_s", "fx_N", "fy_N", "fz_N", "sinkage_m", "fx_std_N", "fy_std_N",
           "sinkage_std_m")  # fmt: skip


def _read_rows(path: pathlib.Path) -> list[dict[str, float]]:
    """The rows of a data file as numbers; ValueError naming the file, line and column of
    the first malformed row (a missing column, a short or long row, a value that is not a
    finite number)."""
    with path.open(newline="", encoding="utf-8") as fh:
        reader = csv.reader(fh)
        header = next(reader, None)
        if header is None:
            raise ValueError(f"{path}: the file is empty")
        missing = [c for c in COLUMNS if c not in header]
        if missing:
            raise ValueError(f"{path}: missing column(s) {', '.join(missing)}")
        where = {c: header.index(c) for c in COLUMNS}
        rows = []
        for fields in reader:
            line = f"{path}: line {reader.line_num} (data row {len(rows) + 1})"
            if not fields:
                continue
            if len(fields) != len(header):
                raise ValueError(
                    f"{line}: {len(fields)} field(s), the header has {len(header)}"
                    " (is the file truncated?)"
                )
            row = {}
            for c, k in where.items():
                try:
                    value = float(fields[k])
                except ValueError:
                    value = math.nan
                if not math.isfinite(value):
                    raise ValueError(f"{line}, column '{c}': {fields[k]!r} is not a finite number")
                row[c] = value
            rows.append(row)
    if not rows:
        raise ValueError(f"{path}: no data rows")
    return rows


def load_single_wheel(folder, wheel: str = "smooth") -> SingleWheelData:
    """Read `smooth_wheel.csv` or `grousered_wheel.csv` from `folder`.

    **Arguments:** `folder`: the data folder (e.g. `../shared/data/3d-terramechanics`);
    `wheel`: "smooth" or "grousered".

    **Returns:** `SingleWheelData` (63 rows).

    **Raises:** `FileNotFoundError` naming the missing file; `ValueError` for an unknown
    wheel, or naming the file, line and column of a missing column, a row with too few or
    too many fields, or a value that is not a finite number.
    """
    if wheel not in SHEARING_RADIUS:
        raise ValueError(f"wheel must be 'smooth' or 'grousered', got {wheel!r}")
    path = pathlib.Path(folder) / f"{wheel}_wheel.csv"
    if not path.is_file():
        raise FileNotFoundError(f"single-wheel data not found: {path}")
    rows = _read_rows(path)
    col = lambda c: np.array([r[c] for r in rows])  # noqa: E731
    radius = SHEARING_RADIUS[wheel]
    beta = col("slip_angle_rad")
    rim = col("rim_speed_m_s") * radius / RIG_RADIUS
    travel = col("travel_speed_m_s")
    heading = travel * np.cos(beta)
    with np.errstate(divide="ignore", invalid="ignore"):
        slip = np.where(rim > 0, 1 - heading / np.where(rim > 0, rim, 1.0), -np.inf)
    in_range = (slip >= -1) & (slip <= 1) & (np.abs(beta) < math.radians(89.0))
    return SingleWheelData(
        wheel=wheel,
        radius=radius,
        width=WHEEL_WIDTH,
        slip_angle_deg=col("slip_angle_deg"),
        slip_angle=beta,
        slip_ratio=col("slip_ratio"),
        rim_speed=rim,
        travel_speed=travel,
        slip=slip,
        fx=col("fx_N"),
        fy=col("fy_N"),
        fz=col("fz_N"),
        sinkage=col("sinkage_m"),
        fx_std=col("fx_std_N"),
        fy_std=col("fy_std_N"),
        sinkage_std=col("sinkage_std_m"),
        in_range=in_range,
    )


# The slip angles [deg] of each group of `single_wheel_study`'s defaults.
STUDY_ANGLES = {"fit": (0, 30, 60), "held_out": (15, 45), "extrapolation": (75,)}


def check_study_rows(data: SingleWheelData, angles=STUDY_ANGLES) -> None:
    """ValueError naming the file and the slip angle if a group of the study has no
    in-range row at one of its angles (a truncated file would otherwise give NaN RMS)."""
    for group, group_angles in angles.items():
        for angle in group_angles:
            if not data.rows((angle,)).any():
                raise ValueError(
                    f"{data.wheel}_wheel.csv: no usable row at slip angle {angle} deg (needed"
                    f" for the {group.replace('_', '-')} rows; the file has"
                    f" {data.fz.shape[0]} rows, the published one 63: is it truncated?)"
                )


@dataclasses.dataclass(frozen=True)
class SingleWheelStudy:
    """Calibration on some slip angles, prediction of the others.

    - `data`: the `SingleWheelData`.
    - `fit`: the chosen `FitResult` (bulldozing on or off, whichever fits the calibration
      rows better); `fits`: both, by `bulldozing` flag.
    - `bulldozing`: the chosen flag.
    - `predicted`: dict "fx", "fy", "sinkage" of model values on every in-range row (NaN
      elsewhere) [N, N, m]; `status`: their `Status` codes (-1 where not solved).
    - `rms`: group -> (F_x [N], F_y [N], sinkage [m], rows) for "fit" (the calibration
      rows), "held_out" (the predicted angles) and "extrapolation".
    - `excluded`: group -> number of rows of those angles outside the model's range.
    - `angles`: group -> the slip angles [deg] of that group.
    """

    data: SingleWheelData
    fit: object
    fits: dict
    bulldozing: bool
    predicted: dict
    status: np.ndarray
    rms: dict
    excluded: dict
    angles: dict


def _start():
    """Start values: the upstream hand-tuned sand (set_soil_params.m) as a Bekker law."""
    terrain = BekkerSoil(
        n=1.46, k_c=0.0, k_phi=8.0e6, cohesion=1.0e3, tan_phi=math.tan(math.radians(29.0)),
        shear_modulus=0.021,
    )  # fmt: skip
    return terrain, WongReece(0.4, 0.2, 0.0)


# Residual scales: a 4 mm sinkage error weighs as much as a 4 N force error (the trial-to-
# trial spread is ~1 mm and ~1 N; fits with each quantity scaled by its RMS matched the
# forces better than needed and the sinkage worse).
RESIDUAL_SCALES = {"sinkage": 0.004, "drawbar_pull": 4.0, "lateral_force": 4.0}
FIT_NAMES = ("n", "k_phi", "cohesion", "tan_phi", "shear_modulus", "c1", "c2",
             "lateral.shear_modulus")  # fmt: skip


def _rms(pred, measured, mask) -> float:
    """Root-mean-square of model - data over the rows in `mask`."""
    return float(np.sqrt(np.mean((pred[mask] - measured[mask]) ** 2)))


def single_wheel_study(
    data: SingleWheelData,
    fit_angles=STUDY_ANGLES["fit"],
    predict_angles=STUDY_ANGLES["held_out"],
    extrapolate_angles=STUDY_ANGLES["extrapolation"],
    max_steps: int = 60,
) -> SingleWheelStudy:
    """Calibrate `BekkerSoil` + `WongReece` + `Lateral` on `fit_angles` with `fit_wheel`
    (sinkage, F_x as drawbar pull, F_y as lateral force; measured F_z as the load), with
    sidewall bulldozing off and on, keep the better calibration (lower scaled SSE on the
    calibration rows only), and predict the rows at `predict_angles` and
    `extrapolate_angles`.

    Fitted: n, k_phi (k_c = 0), cohesion, tan phi, K, c1, c2, K_y; held: c3 = 0, the
    bulldozing unit weight (1330 kg/m^3 x g, the measured bulk density).

    **Returns:** `SingleWheelStudy`; RMS errors are model - data over the named rows.

    **Raises:** `ValueError` if one of the angles has no in-range row (`check_study_rows`).
    """
    angles = {"fit": fit_angles, "held_out": predict_angles, "extrapolation": extrapolate_angles}
    check_study_rows(data, angles)
    wheel = RigidWheel(2 * data.radius, data.width)
    terrain, dist = _start()
    sel = data.rows(fit_angles)
    fits = {}
    for bulldozing in (False, True):
        lateral = Lateral(0.021, SAND_UNIT_WEIGHT, bulldozing=bulldozing)
        measured = {"sinkage": data.sinkage[sel], "drawbar_pull": data.fx[sel],
                    "lateral_force": data.fy[sel]}  # fmt: skip
        fits[bulldozing] = fit_wheel(
            wheel, ContactModel(terrain, dist, lateral=lateral), data.fz[sel], data.slip[sel],
            measured, slip_angle=data.slip_angle[sel], fit=FIT_NAMES, max_steps=max_steps,
            scale=RESIDUAL_SCALES,
        )  # fmt: skip
    bulldozing = bool(fits[True].sse < fits[False].sse)
    best = fits[bulldozing]
    rows = np.flatnonzero(data.in_range)
    fitted = ContactModel(
        best.info["terrain"], best.info["distribution"], lateral=best.info["lateral"]
    )
    st = solve_wheel(
        wheel, fitted, data.fz[rows], data.slip[rows], slip_angle=data.slip_angle[rows]
    )  # fmt: skip
    n = data.fz.shape[0]
    predicted = {k: np.full(n, np.nan) for k in ("fx", "fy", "sinkage")}
    status = np.full(n, -1)
    predicted["fx"][rows] = np.asarray(st.drawbar_pull)
    predicted["fy"][rows] = np.asarray(st.lateral_force)
    predicted["sinkage"][rows] = np.asarray(st.sinkage)
    status[rows] = np.asarray(st.status)
    rms, excluded = {}, {}
    for group, group_angles in angles.items():
        mask = data.rows(group_angles)
        rms[group] = (
            _rms(predicted["fx"], data.fx, mask),
            _rms(predicted["fy"], data.fy, mask),
            _rms(predicted["sinkage"], data.sinkage, mask),
            int(mask.sum()),
        )
        all_rows = np.isin(np.round(data.slip_angle_deg), list(group_angles))
        excluded[group] = int((all_rows & ~data.in_range).sum())
    return SingleWheelStudy(data, best, fits, bulldozing, predicted, status, rms, excluded, angles)


def study_table_markdown(studies) -> str:
    """Markdown table of fit / held-out / extrapolation RMS per wheel beside upstream."""
    lines = [
        "| wheel | rows | F_x RMS [N] | F_y RMS [N] | sinkage RMS [mm] | rows used (left out) |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    names = {"fit": "fit", "held_out": "held out", "extrapolation": "extrapolation"}
    for st in studies:
        for group, (fx, fy, z, n) in st.rms.items():
            angles = ", ".join(f"{a}°" for a in st.angles[group])
            lines.append(
                f"| {st.data.wheel} | {names[group]}: β = {angles} | {fx:.1f} | {fy:.1f} | "
                f"{1000 * z:.1f} | {n} ({st.excluded[group]}) |"
            )
        ux, uy, uz = UPSTREAM_RMS[st.data.wheel]
        lines.append(
            f"| {st.data.wheel} | upstream 3-D model, fitted in-sample, β ≤ 60° | {ux:.1f} | "
            f"{uy:.1f} | {1000 * uz:.1f} | 45 (0) |"
        )
    return "\n".join(lines)


def single_wheel_figure(study: SingleWheelStudy, path) -> pathlib.Path:
    """Predicted vs measured F_x and F_y against the data set's slip ratio, one panel per
    slip angle (error bars: the measured spread over 3 trials); PNG at `path`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d = study.data
    angles = sorted(set(np.round(d.slip_angle_deg).astype(int)))
    fig, axes = plt.subplots(2, len(angles), figsize=(2.3 * len(angles), 5.2), sharex=True)
    role = {a: g for g, group in study.angles.items() for a in group}
    labels = {"fit": "fitted", "held_out": "predicted", "extrapolation": "extrapolated"}
    for k, a in enumerate(angles):
        rows = np.round(d.slip_angle_deg) == a
        order = np.argsort(d.slip_ratio[rows])
        for r, (q, std, name) in enumerate(((d.fx, d.fx_std, "F_x"), (d.fy, d.fy_std, "F_y"))):
            ax = axes[r, k]
            x = d.slip_ratio[rows][order]
            ax.errorbar(x, q[rows][order], yerr=std[rows][order], fmt="o", ms=3, color="k",
                        capsize=2, label="measured")  # fmt: skip
            pred = study.predicted["fx" if r == 0 else "fy"][rows][order]
            ax.plot(x, pred, "-", color="C0" if role.get(a) == "fit" else "C3",
                    label=labels.get(role.get(a, ""), "model"))  # fmt: skip
            ax.axhline(0, color="0.8", lw=0.8)
            if r == 0:
                ax.set_title(f"β = {a}°" + (f"\n({labels[role[a]]})" if a in role else
                                            "\n(outside the model)"))  # fmt: skip
            if k == 0:
                ax.set_ylabel(f"{name} [N]")
            if r == 1:
                ax.set_xlabel("slip ratio s [-]")
        axes[0, k].legend(fontsize=6, loc="lower right")
    fig.suptitle(
        f"{d.wheel} wheel in sand (robomechanics/3d-terramechanics): snowjax calibrated on "
        f"β = {', '.join(str(a) for a in study.angles['fit'])}°"
        f" (bulldozing {'on' if study.bulldozing else 'off'})",
        fontsize=9,
    )
    fig.tight_layout()
    path = pathlib.Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_single_wheel(out, folder, progress: bool = False) -> list[pathlib.Path]:
    """Run `single_wheel_study` on both wheels in `folder` and write
    `single_wheel.md` (the RMS table), `single_wheel_<wheel>.png` and
    `single_wheel_predictions.csv` to `out`.  Returns the written paths.

    Both data files are read and checked first (`load_single_wheel`, `check_study_rows`):
    a missing or malformed file raises `FileNotFoundError` / `ValueError` before anything
    is computed."""
    out = pathlib.Path(out)
    # Both files are read and checked before the first (minutes-long) calibration.
    data = {wheel: load_single_wheel(folder, wheel) for wheel in ("smooth", "grousered")}
    for d in data.values():
        check_study_rows(d)
    out.mkdir(parents=True, exist_ok=True)
    studies, files = [], []
    for wheel, d in data.items():
        if progress:
            print(f"calibrating the {wheel} wheel (bulldozing off and on) ...", flush=True)
        st = single_wheel_study(d)
        studies.append(st)
        files.append(single_wheel_figure(st, out / f"single_wheel_{wheel}.png"))
    table = out / "single_wheel.md"
    table.write_text(study_table_markdown(studies) + "\n", encoding="utf-8")
    files.append(table)
    csv_path = out / "single_wheel_predictions.csv"
    with csv_path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["wheel", "slip_angle_deg", "slip_ratio", "slip", "fz_N", "fx_N", "fx_model_N",
                    "fy_N", "fy_model_N", "sinkage_m", "sinkage_model_m", "status"])  # fmt: skip
        for st in studies:
            d = st.data
            for k in range(d.fz.shape[0]):
                w.writerow([d.wheel, d.slip_angle_deg[k], d.slip_ratio[k], d.slip[k], d.fz[k],
                            d.fx[k], st.predicted["fx"][k], d.fy[k], st.predicted["fy"][k],
                            d.sinkage[k], st.predicted["sinkage"][k], st.status[k]])  # fmt: skip
    files.append(csv_path)
    return files
