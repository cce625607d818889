"""Chapter 3 of Sankapalli (2004), sections 3.1–3.3: the tyre's shear force model.

Figs 3.1 and 3.3–3.12: the normalised slips, the load functions (3.17)–(3.21) against
the FEA data of Table 3.2, and the shear force variation studies of section 3.3.  The
pure and combined forces of section 3.4 (Figs 3.13–3.16) are in `chapter3_forces.py`.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .._tire.sensitivity import shear_force_variation_ratios
from .._tire.slip import normalized_lateral_slip, normalized_longitudinal_slip
from .._tire.tire import (
    contact_pressure_constant,
    lateral_friction,
    lateral_stiffness,
    longitudinal_friction,
    longitudinal_stiffness,
    pure_longitudinal_force,
    tire_forces,
    tire_parameters,
)
from .plotting import subplots, thesis_title
from .spec import Context, FigureResult, figure

# Chapter 3 operating points the thesis does not state.
SLIP_ANGLE_DEG = 10.0  # Figs 3.1, 3.14, 3.16
SLIP_ANGLES_DEG = (2.0, 5.0, 10.0, 20.0)  # Figs 3.1, 3.13
TREND_LOADS = (3500.0, 10000.0)  # Figs 3.8-3.12: mu_x(3.5 kN) = 0.3938, mu_x(10 kN) = 0.1696
# Trend curves of Figs 3.7/3.9/3.11: the load function's increment p(F) - p(F_1) scaled by
# these factors (the middle curve is the thesis's load function).
TREND_FACTORS = {
    "c_s": (0.5, 1.0, 2.0),
    "e1": (0.5, 1.0, 1.3),  # 1.3 keeps E1 <= 0.5 (Table 3.1) up to 10 kN
    "mu_x": (0.5, 1.0, 1.1),  # 1.1 keeps mu_x F_z at 10 kN above its 3.5 kN value
}


@functools.cache
def table_3_2() -> dict[float, tuple]:
    """Table 3.2 of the thesis (FEA data, shipped as snowjax/data/table_3_2.csv).

    F_z [kN] -> (C_s [kN/rad], C_alpha [kN/rad], mu_x, mu_y, E1); also importable as
    `TABLE_3_2` from this module.
    """
    from .._fit.tire import thesis_tire_table

    return {
        float(f): (cs, ca, mux, muy, e1)
        for f, cs, ca, mux, muy, e1 in zip(*thesis_tire_table().values())
    }


def __getattr__(name: str):
    if name == "TABLE_3_2":  # read on first use: the fit module is imported lazily
        return table_3_2()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@figure(
    "3.1",
    "friction coefficients and normalised slips",
    "The thesis's Figure 3.1 is a sketch; drawn here: (a) normalised slips "
    "φ_x (3.7), φ_y (3.8), φ (3.9) of the thesis tyre at 5 kN and α = 10° "
    "(assumed operating point), (b) the combined force (3.14)–(3.15) over slip "
    "0…1 inside the friction ellipse μ_x F_z, μ_y F_z.",
    ("3.7", "3.8", "3.9", "3.10", "3.14", "3.15", "3.19", "3.20"),
)
def fig_3_1(ctx: Context) -> FigureResult:
    load = 5000.0
    alpha = math.radians(SLIP_ANGLE_DEG)
    slips = np.linspace(0.0, 1.0, ctx.n_curve)
    p = tire_parameters(load)
    phi_x = np.asarray(normalized_longitudinal_slip(load, slips, p.c_s, p.mu_x))
    phi_y = np.asarray(normalized_lateral_slip(load, slips, alpha, p.c_alpha, p.mu_y))
    phi = np.hypot(phi_x, phi_y)
    mu_x, mu_y = float(p.mu_x), float(p.mu_y)
    angles = np.radians(np.array(SLIP_ANGLES_DEG))
    f = tire_forces(load, slips[None, :], angles[:, None])

    fig, (ax1, ax2) = subplots(1, 2, figsize=(11, 4.4))
    ax1.plot(slips, phi_x, "-", label="φ_x (3.7)")
    ax1.plot(slips, phi_y, "--", label="φ_y (3.8)")
    ax1.plot(slips, phi, ":", color="k", label="φ (3.9)")
    ax1.set_xlabel("driving slip i [-]")
    ax1.set_ylabel("normalised slip [-]")
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)
    ax1.set_title(f"(a) normalised slips, F_z = 5 kN, α = {SLIP_ANGLE_DEG:g}°", fontsize=9)
    t = np.linspace(0, np.pi / 2, 60)
    ax2.plot(
        mu_x * np.cos(t),
        mu_y * np.sin(t),
        "-",
        color="k",
        label=f"friction ellipse μ_x = {mu_x:.3f}, μ_y = {mu_y:.3f}",
    )
    for k, a in enumerate(SLIP_ANGLES_DEG):
        ax2.plot(
            np.asarray(f.fx_combined[k]) / load,
            np.asarray(f.fy_combined[k]) / load,
            "-",
            color=f"C{k}",
            label=f"combined force / F_z, α = {a:g}°",
        )
    ax2.set_xlabel("F_x / F_z [-]")
    ax2.set_ylabel("F_y / F_z [-]")
    ax2.set_aspect("equal")
    ax2.set_ylim(0, 1.6 * mu_y)
    ax2.legend(fontsize=7, loc="upper right")
    ax2.grid(alpha=0.3)
    ax2.set_title("(b) combined force on the friction ellipse (slip 0…1)", fontsize=9)
    fig.suptitle("Fig. 3.1 (cf. thesis): friction coefficients and normalised slips", fontsize=10)
    fig.tight_layout()
    rows = [[s, a, b_, c] for s, a, b_, c in zip(slips, phi_x, phi_y, phi)]
    fx_n = np.asarray(f.fx_combined) / (mu_x * load)
    fy_n = np.asarray(f.fy_combined) / (mu_y * load)
    ell = float(np.max(fx_n**2 + fy_n**2))
    comparison = (
        "Figure 3.1 of the thesis is a sketch of the friction coefficients μ_x, μ_y and of "
        "the normalised slips φ_x (3.7), φ_y (3.8) and φ (3.9); the text gives no numbers "
        "for it. We draw the quantities themselves for the thesis tyre at 5 kN (load "
        f"functions 3.17–3.21: μ_x = {mu_x:.4f}, μ_y = {mu_y:.4f}). (a) φ_x grows linearly "
        "with slip, φ_y falls with (1 − i) (the factor 1 + S_x of 3.8, S_x = −i); φ is "
        "their Euclidean norm. (b) The combined force of (3.14)–(3.15) stays inside the "
        f"ellipse with semi-axes μ_x F_z, μ_y F_z: max (F_x/μ_xF_z)² + (F_y/μ_yF_z)² = "
        f"{ell:.4f} ≤ 1, as N(φ) ≤ 1 requires."
    )
    return FigureResult(
        fig,
        ["slip", "phi_x", "phi_y", "phi"],
        rows,
        comparison,
        verdict="a sketch in the thesis; the quantities drawn from (3.7)–(3.9) "
        "are consistent with it (force inside the friction ellipse)",
    )


def _load_function_figure(ctx, number, title, quantities, equations_text):
    """Shared body of Figs 3.3-3.5: fitted load functions vs Table 3.2."""
    loads_kn = np.linspace(3.0, 8.0, ctx.n_curve)
    table_kn = np.array(list(table_3_2()))
    fig, ax = subplots(figsize=(6.4, 4.4))
    csv_cols = ["load_kN"]
    curves = []
    t_cols = ["load [kN]"]
    t_rows = [[f] for f in table_kn]
    worst = []
    for k, (name, col, fn, scale, unit) in enumerate(quantities):
        curve = np.asarray(fn(loads_kn * 1e3)) / scale
        at_table = np.asarray(fn(table_kn * 1e3)) / scale
        fea = np.array([table_3_2()[f][col] for f in table_kn])
        ax.plot(loads_kn, curve, "-", color=f"C{k}", label=f"{name}, fit")
        ax.plot(table_kn, fea, "o", color=f"C{k}", label=f"{name}, FEA (Table 3.2)")
        csv_cols.append(f"{name}_fit{unit}")
        curves.append(curve)
        t_cols += [f"{name} FEA", f"{name} fit", f"{name} diff [%]"]
        rel = 100 * (at_table / fea - 1)
        for r, a, b_, c in zip(t_rows, fea, at_table, rel):
            r += [a, b_, c]
        worst.append((name, float(np.max(np.abs(rel))), float(table_kn[np.argmax(np.abs(rel))])))
    ax.set_xlabel("normal load F_z [kN]")
    ax.set_ylabel(f"{title} {quantities[0][4]}")
    thesis_title(ax, number, title + " " + equations_text)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    rows = [[f] + [float(c[j]) for c in curves] for j, f in enumerate(loads_kn)]
    return fig, csv_cols, rows, t_cols, t_rows, worst


@figure(
    "3.3",
    "tyre stiffness: fit vs FEA data",
    "Load functions (3.17), (3.18) with the published coefficients (A4 = 0.2026, "
    "A5 = 0.1516, B4 = 0.1936, B5 = 0.1190) vs the FEA values of Table 3.2.",
    ("3.17", "3.18"),
)
def fig_3_3(ctx):
    fig, cols, rows, tc, tr, worst = _load_function_figure(
        ctx,
        "3.3",
        "tyre stiffness",
        [
            ("C_s", 0, longitudinal_stiffness, 1e3, "[kN/rad]"),
            ("C_α", 1, lateral_stiffness, 1e3, "[kN/rad]"),
        ],
        "(3.17), (3.18)",
    )
    comparison = (
        'The thesis says the fitted functions reproduce the FEA data "well in both '
        'magnitude and trend". With the published coefficients the largest deviations '
        f"from Table 3.2 are {worst[0][1]:.1f} % for C_s (at {worst[0][2]:g} kN) and "
        f"{worst[1][1]:.1f} % for C_α (at {worst[1][2]:g} kN). The form F_z/(A + B F_z) "
        "is concave and cannot follow the table's jump between 6.24 and 7.5 kN (C_s rises "
        "by 16 % there after 2 % over the previous 1.7 kN), so the fit passes through the "
        "middle of the points; the trend (increasing C, decreasing C/F_z) is right."
    )
    return FigureResult(
        fig,
        cols,
        rows,
        comparison,
        tc,
        tr,
        verdict=f"trend reproduced; fit within {worst[0][1]:.1f} % (C_s) and "
        f"{worst[1][1]:.1f} % (C_α) of Table 3.2",
    )


@figure(
    "3.4",
    "friction coefficients: fit vs FEA data",
    "Load functions (3.19), (3.20) with the published coefficients vs Table 3.2.",
    ("3.19", "3.20"),
)
def fig_3_4(ctx):
    fig, cols, rows, tc, tr, worst = _load_function_figure(
        ctx,
        "3.4",
        "friction coefficient",
        [
            ("μ_x", 2, longitudinal_friction, 1.0, "[-]"),
            ("μ_y", 3, lateral_friction, 1.0, "[-]"),
        ],
        "(3.19), (3.20)",
    )
    comparison = (
        "The thesis shows the quadratic fits (3.19), (3.20) on the FEA friction "
        "coefficients. We reproduce that agreement: the largest deviations from Table 3.2 "
        f"are {worst[0][1]:.2f} % (μ_x, {worst[0][2]:g} kN) and {worst[1][1]:.2f} % "
        f"(μ_y, {worst[1][2]:g} kN). Both decrease with load, μ_y faster than μ_x."
    )
    return FigureResult(
        fig,
        cols,
        rows,
        comparison,
        tc,
        tr,
        verdict=f"agrees: fit within {max(worst[0][1], worst[1][1]):.2f} % of Table 3.2",
    )


@figure(
    "3.5",
    "contact pressure constant: fit vs FEA data",
    "Load function (3.21) with a1 = 7.5852e-9, a2 = 0.1203 vs Table 3.2.",
    ("3.21",),
)
def fig_3_5(ctx):
    fig, cols, rows, tc, tr, worst = _load_function_figure(
        ctx,
        "3.5",
        "contact pressure constant",
        [("E1", 4, contact_pressure_constant, 1.0, "[-]")],
        "(3.21)",
    )
    e1_35 = float(contact_pressure_constant(3500.0))
    comparison = (
        "The thesis says the fitted E1 (3.21) matches the FEA data. With the published "
        f"a1 = 7.6e-9, a2 = 0.1203 it does at 6.24 kN, but not at light loads: "
        f"E1(3.5 kN) = {e1_35:.4f} against 0.0402 in Table 3.2 (largest deviation "
        f"{worst[0][1]:.0f} % at {worst[0][2]:g} kN). The form 0.5[1 − exp(−a1²F − a2²F²)] "
        "with a1 ≈ 0 is a Gaussian-type rise that cannot be both flat below 4.5 kN and "
        "steep above 6 kN as the table is; a refit of Table 3.2 returns essentially the "
        "published coefficients, so this is the limit of the form, not a typo."
    )
    return FigureResult(
        fig,
        cols,
        rows,
        comparison,
        tc,
        tr,
        verdict=f"partly: good at 6.24 kN, {worst[0][1]:.0f} % off at "
        f'{worst[0][2]:g} kN — the thesis\'s "matches" does not hold '
        "at light loads",
    )


@figure(
    "3.6",
    "shear force variation ratios",
    "Shear force variation ratios of section 3.3.1 (pure longitudinal slip, "
    "3.11) due to C_s, μ_x and E1 between 3.5 and 7.5 kN (assumed: the ends of "
    "the FEA load range; the thesis does not state the loads).",
    ("3.10", "3.11", "3.17", "3.19", "3.21"),
)
def fig_3_6(ctx):
    slips = np.linspace(0.0, 1.0, ctx.n_curve)
    r = shear_force_variation_ratios(slips)
    st, fr, e1 = (np.asarray(x) for x in (r.stiffness, r.friction, r.pressure_constant))
    fig, ax = subplots(figsize=(6.4, 4.4))
    ax.plot(slips, st, "-", label="due to C_s")
    ax.plot(slips, fr, "--", label="due to μ_x")
    ax.plot(slips, e1, "-.", label="due to E1")
    ax.set_xlabel("longitudinal slip i [-]")
    ax.set_ylabel("shear force variation ratio [-]")
    thesis_title(ax, "3.6", "variation ratios, 3.5 → 7.5 kN")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    rows = [[s, a, b_, c] for s, a, b_, c in zip(slips, st, fr, e1)]
    cross = np.nonzero((e1[1:] > st[1:]) & (e1[:-1] <= st[:-1]))[0]
    cross_txt = (
        f"the E1 ratio overtakes the stiffness ratio at slip ≈ {slips[cross[0] + 1]:.2f}"
        if cross.size
        else "the E1 ratio never overtakes the stiffness ratio"
    )
    fr_least = bool(np.all(fr[1:] <= np.minimum(st, e1)[1:]))
    slope_e1 = float(np.mean(np.diff(e1) > np.diff(st)))
    comparison = (
        "The thesis (section 3.3.1) says the ratios are always positive, tyre stiffness "
        "has the greatest and friction the least influence in magnitude, E1 has the "
        "greater slope up to slip 0.8, and at full slip the force is sensitive to neither "
        "stiffness nor contact pressure. The loads are not stated; we use the ends of the "
        f"FEA range, 3.5 and 7.5 kN. Minima: {st.min():.3f} (C_s), {fr.min():.3f} (μ_x), "
        f"{e1.min():.3f} (E1): never negative (confirmed). Friction has the least "
        f"influence at every slip > 0: {'confirmed' if fr_least else 'not confirmed'}. "
        f"Stiffness has the greatest influence only at small slip: {cross_txt}. E1 has "
        f"the steeper curve on {100 * slope_e1:.0f} % of the slip grid, mostly below 0.6. "
        f"At slip 1 the ratios are {st[-1]:.2f} (C_s), {fr[-1]:.2f} (μ_x), {e1[-1]:.2f} "
        "(E1): they are not small, because every numerator of the thesis's ratios also "
        "changes the load from F_z1 to F_z2, and near full slip F_x ≈ μ_x F_z; but the "
        "C_s and E1 curves meet there, i.e. the force no longer depends on which of the "
        'two changed — our reading of "sensitive to neither".'
    )
    over = f"above slip {slips[cross[0] + 1]:.2f}" if cross.size else "nowhere"
    return FigureResult(
        fig,
        ["slip", "ratio_c_s", "ratio_mu_x", "ratio_e1"],
        rows,
        comparison,
        verdict="positivity and 'friction least' confirmed; 'stiffness "
        f"greatest' fails {over}, where E1 overtakes it",
    )


def _trend_figure(ctx, number, pname, label, unit, claim):
    """Figs 3.8 / 3.10 / 3.12: shear force variation for three trends of one parameter."""
    f1, f2 = TREND_LOADS
    loads = np.linspace(f1, f2, ctx.n_curve)
    base_curve = np.asarray(getattr(tire_parameters(loads), pname))
    p1 = tire_parameters(f1)
    p2 = tire_parameters(f2)
    base1 = float(getattr(p1, pname))
    slips = np.linspace(0.0, 1.0, ctx.n_curve)

    def fx(load, p, **over):
        q = {n: float(getattr(p, n)) for n in ("c_s", "mu_x", "e1")}
        q.update(over)
        return np.asarray(pure_longitudinal_force(load, slips, q["c_s"], q["mu_x"], q["e1"]))

    f_base = fx(f1, p1)
    names = ("A", "B", "C") if pname != "mu_x" else ("a", "b", "c")
    factors = TREND_FACTORS[pname]
    trends, variations = {}, {}
    for name, fac in zip(names, factors):
        trends[name] = base1 + fac * (base_curve - base1)
        value2 = base1 + fac * (float(getattr(p2, pname)) - base1)
        variations[name] = fx(f2, p2, **{pname: value2}) - f_base
    scale = 1e3 if pname == "c_s" else 1.0

    fig, (ax1, ax2, ax3) = subplots(1, 3, figsize=(13, 4.2))
    for k, name in enumerate(names):
        ax1.plot(
            loads / 1e3,
            trends[name] / scale,
            "-",
            color=f"C{k}",
            label=f"{name}: {factors[k]:g} × increment of the fit",
        )
        ax2.plot(slips, variations[name], "-", color=f"C{k}", label=f"curve {name}")
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.where(f_base > 0, variations[name] / f_base, np.nan)
        ax3.plot(slips, rel, "-", color=f"C{k}", label=f"curve {name}")
    ax1.set_xlabel("normal load F_z [kN]")
    ax1.set_ylabel(f"{label} {unit}")
    ax1.set_title(f"(a) trends of {label} (cf. thesis Fig. {_TREND_FIG[number]})", fontsize=9)
    ax2.set_xlabel("longitudinal slip i [-]")
    ax2.set_ylabel("ΔF_x = F_x(F_z2) − F_x(F_z1) [N]")
    ax2.set_title("(b) shear force variation (3.11)", fontsize=9)
    ax3.set_xlabel("longitudinal slip i [-]")
    ax3.set_ylabel("ΔF_x / F_x(F_z1) [-]")
    ax3.set_title("(c) relative shear force variation", fontsize=9)
    for ax in (ax1, ax2, ax3):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(
        f"Fig. {number} (cf. thesis): shear force variation for changed {label} "
        f"trends, F_z {f1 / 1e3:g} → {f2 / 1e3:g} kN",
        fontsize=10,
    )
    fig.tight_layout()
    rows = [[s] + [float(variations[n][j]) for n in names] for j, s in enumerate(slips)]
    summary = "; ".join(
        f"curve {n}: ΔF_x peaks at {variations[n].max():.0f} N (slip "
        f"{slips[np.argmax(variations[n])]:.2f}), {variations[n][-1]:.0f} N at slip 1"
        for n in names
    )
    comparison = (
        claim + " We read the thesis's garbled definitions (\"F_x(F_z1, …) − "
        '12(random1)") as: each curve is F_x(F_z2, parameters at F_z2) − '
        "F_x(F_z1, parameters at F_z1) by (3.11), with the studied parameter at "
        "F_z2 taken from its trend curve and the others from the load functions. "
        f"We find {summary}."
    )
    return FigureResult(fig, ["slip"] + [f"delta_Fx_{n}_N" for n in names], rows, comparison)


_TREND_FIG = {"3.8": "3.7", "3.10": "3.9", "3.12": "3.11"}


@figure(
    "3.8",
    "shear force variation for changed stiffness trends",
    "(a) Three C_s trends (cf. Fig. 3.7): B = (3.17), A and C with 0.5 and 2 "
    "times its increment over 3.5–10 kN (assumed); (b) ΔF_x = F_x(10 kN) − "
    "F_x(3.5 kN) by (3.11); (c) ΔF_x relative to F_x(3.5 kN).",
    ("3.11", "3.17", "3.19", "3.21"),
)
def fig_3_8(ctx):
    res = _trend_figure(
        ctx,
        "3.8",
        "c_s",
        "C_s",
        "[kN/rad]",
        "Thesis (3.3.2): three stiffness trends OA < OB < OC (Fig. 3.7); the shear force "
        "variation increases for slips up to 0.2, decreases between 0.2 and 0.5 and is the "
        "same for all stiffnesses at full slip. The trends themselves are not given: B is "
        "the load function (3.17) from 3.5 to 10 kN, A and C scale its increment by 0.5 "
        "and 2 (C_s/F_z still decreasing).",
    )
    v = np.array([r[1:] for r in res.rows])
    res.comparison += (
        " Qualitatively confirmed: a stiffer trend gives a larger variation at small "
        "slip, the curves rise to a peak and fall, and they converge at large slip "
        f"(spread {np.ptp(v[-1]):.0f} N at slip 1 vs {np.ptp(v, axis=1).max():.0f} N at "
        "most)."
    )
    res.verdict = (
        "confirmed: stiffer trend → larger variation at small slip, peak then "
        "decline, one common value at full slip"
    )
    return res


@figure(
    "3.10",
    "shear force variation for changed contact-pressure-constant trends",
    "(a) Three E1 trends (cf. Fig. 3.9): B = (3.21), A and C with 0.5 and 1.3 "
    "times its increment over 3.5–10 kN (assumed); (b), (c) as in Fig. 3.8.",
    ("3.10", "3.11", "3.21"),
)
def fig_3_10(ctx):
    res = _trend_figure(
        ctx,
        "3.10",
        "e1",
        "E1",
        "[-]",
        "Thesis (3.3.3): for steeper E1 trends (Fig. 3.9) the slope of the relative shear "
        "force increases up to slip 0.6, and at full slip all curves coincide. The trends "
        "are not given: B is the load function (3.21) from 3.5 to 10 kN, A and C scale "
        "its increment by 0.5 and 1.3 (C stays below the bound E1 = 0.5 of Table 3.1).",
    )
    v = np.array([r[1:] for r in res.rows])
    res.comparison += (
        " Confirmed in trend: a steeper E1 trend gives a larger variation at "
        f"intermediate slip (at slip 0.5: {', '.join(f'{x:.0f}' for x in v[len(v) // 2])} N "
        "for A, B, C), and the curves approach each other at high slip "
        f"(spread {np.ptp(v[-1]):.0f} N at slip 1)."
    )
    res.verdict = (
        "confirmed: steeper E1 trend → larger (relative) variation up to slip "
        "≈ 0.6, common value at full slip"
    )
    return res


@figure(
    "3.12",
    "shear force variation for changed friction trends",
    "(a) Three μ_x trends (cf. Fig. 3.11): b = (3.19) from 0.3938 to 0.1696 over "
    "3.5–10 kN (as in the thesis), a and c with 0.5 and 1.1 times its decrease "
    "(assumed); (b), (c) as in Fig. 3.8.",
    ("3.11", "3.19"),
)
def fig_3_12(ctx):
    res = _trend_figure(
        ctx,
        "3.12",
        "mu_x",
        "μ_x",
        "[-]",
        "Thesis (3.3.4): curve b is (3.19) from 0.3938 to 0.1696 (3.5 to 10 kN); a lies "
        'above, c below (Fig. 3.11). For c the relative shear force is "unstable" at '
        "slips up to 0.25 and then increases; at full slip it is constant. We take a and "
        "c as 0.5 and 1.1 times b's decrease (with 1.1, μ_x F_z at 10 kN stays above its "
        "3.5 kN value, as the thesis requires of the trends). Note that (3.19) itself "
        "does not increase μ_x F_z monotonically: μ_x F_z peaks at about 7.3 kN.",
    )
    v = np.array([r[1:] for r in res.rows])
    sl = np.array([r[0] for r in res.rows])
    c = v[:, 2]
    k_pk = int(np.argmax(c))
    k_min = k_pk + int(np.argmin(c[k_pk:]))
    res.comparison += (
        f" Curve c rises to {c[k_pk]:.0f} N at slip {sl[k_pk]:.2f}, falls to "
        f"{c[k_min]:.0f} N at slip {sl[k_min]:.2f}"
        + (
            f" and recovers to {c[-1]:.0f} N at slip 1"
            if k_min < len(c) - 1
            else " (its value at slip 1)"
        )
        + ": the early turn matches the thesis's change of behaviour near slip 0.25 (we "
        'read "unstable" as this non-monotonic stretch), but it then falls instead of '
        "rising: the low friction at F_z2 saturates the tyre early, and near full slip "
        "only μ_x2 F_z2 − μ_x1 F_z1 is left. A higher friction trend (a) gives a larger "
        f"variation at every slip ({v[-1, 0]:.0f} N at slip 1), and all three curves are "
        "flat near full slip (constant, as the thesis says)."
    )
    res.verdict = (
        "partly: a > b > c and constant at full slip confirmed; c turns near slip "
        "0.2 but then falls instead of rising"
    )
    return res
