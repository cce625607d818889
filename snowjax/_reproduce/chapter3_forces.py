"""Chapter 3 of Sankapalli (2004), section 3.4: pure and combined forces (Figs 3.13–3.16).

The resultant shear forces (3.13), (3.16) and their directions against slip, slip angle
and load, and isotropic against anisotropic friction.  Sections 3.1–3.3 are in
`chapter3.py`.
"""

from __future__ import annotations

import math

import numpy as np

from .._tire.tire import TireParameters, tire_forces, tire_forces_from_parameters, tire_parameters
from .chapter3 import SLIP_ANGLE_DEG, SLIP_ANGLES_DEG
from .plotting import subplots, thesis_title
from .spec import FigureResult, figure

# Loads of Figs 3.13, 3.14 (the thesis does not state them).
TIRE_LOADS = (3500.0, 5000.0, 7500.0)  # [N]


@figure(
    "3.13",
    "|F_pure| vs |F_combined|",
    "Pure (3.13) and combined (3.16) resultant shear forces vs driving slip: "
    "(a) at 5 kN for α = 2, 5, 10, 20°; (b) at α = 10° for 3.5, 5, 7.5 kN "
    "(assumed operating points). Load functions (3.17)–(3.21).",
    ("3.7", "3.8", "3.9", "3.10", "3.11", "3.12", "3.13", "3.14", "3.15", "3.16"),
)
def fig_3_13(ctx):
    slips = np.linspace(0.0, 1.0, ctx.n_curve)
    angles = np.radians(np.array(SLIP_ANGLES_DEG))
    f5 = tire_forces(5000.0, slips[None, :], angles[:, None])
    loads = np.array(TIRE_LOADS)
    fl = tire_forces(loads[:, None], slips[None, :], math.radians(SLIP_ANGLE_DEG))
    fig, (ax1, ax2) = subplots(1, 2, figsize=(11, 4.4))
    for k, a in enumerate(SLIP_ANGLES_DEG):
        ax1.plot(slips, np.asarray(f5.pure[k]), "-", color=f"C{k}", label=f"F_pure, α = {a:g}°")
        ax1.plot(
            slips, np.asarray(f5.combined[k]), "--", color=f"C{k}", label=f"F_combined, α = {a:g}°"
        )
    for k, load in enumerate(loads):
        ax2.plot(
            slips, np.asarray(fl.pure[k]), "-", color=f"C{k}", label=f"F_pure, {load / 1e3:g} kN"
        )
        ax2.plot(
            slips,
            np.asarray(fl.combined[k]),
            "--",
            color=f"C{k}",
            label=f"F_combined, {load / 1e3:g} kN",
        )
    ax1.set_title("(a) F_z = 5 kN, several slip angles", fontsize=9)
    ax2.set_title(f"(b) α = {SLIP_ANGLE_DEG:g}°, several loads", fontsize=9)
    for ax in (ax1, ax2):
        ax.set_xlabel("driving slip i [-]")
        ax.set_ylabel("|F| [N]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=2)
    fig.suptitle("Fig. 3.13 (cf. thesis): |F_pure| (3.13) vs |F_combined| (3.16)", fontsize=10)
    fig.tight_layout()
    pure, comb = np.asarray(f5.pure), np.asarray(f5.combined)
    rows = [
        [s]
        + [float(pure[k, j]) for k in range(len(angles))]
        + [float(comb[k, j]) for k in range(len(angles))]
        for j, s in enumerate(slips)
    ]
    cols = (
        ["slip"]
        + [f"F_pure_alpha{a:g}deg_N" for a in SLIP_ANGLES_DEG]
        + [f"F_combined_alpha{a:g}deg_N" for a in SLIP_ANGLES_DEG]
    )
    diff = np.concatenate(
        [(pure - comb).ravel(), (np.asarray(fl.pure) - np.asarray(fl.combined)).ravel()]
    )
    inc_pure = bool(np.all(np.diff(pure, axis=0) >= -1e-9))
    dec_comb = np.all(np.diff(comb, axis=0) <= 1e-9, axis=0)
    first_dec = (
        slips[np.argmax(dec_comb & (slips > 0))] if np.any(dec_comb & (slips > 0)) else float("nan")
    )
    load_inc = bool(
        np.all(np.diff(np.asarray(fl.pure), axis=0) >= -1e-9)
        and np.all(np.diff(np.asarray(fl.combined), axis=0) >= -1e-9)
    )
    comparison = (
        "Thesis (3.4.1): F_pure is always greater than F_combined; at constant load, as the "
        "slip angle increases F_pure increases whereas F_combined decreases; at constant "
        "slip angle both increase with load. Slip angles and loads are not given; we use "
        f"α = {', '.join(f'{a:g}' for a in SLIP_ANGLES_DEG)}° at 5 kN and 3.5/5/7.5 kN at "
        f"α = {SLIP_ANGLE_DEG:g}°. min (F_pure − F_combined) = {diff.min():.2g} N on all "
        "curves, i.e. ≥ 0 to rounding (equal at slip 0): confirmed. F_pure increases with α "
        "at every slip: "
        f"{'confirmed' if inc_pure else 'not everywhere'}. F_combined decreases with α only "
        f"for slips ≥ {first_dec:.2f} on this grid (at small slip the lateral slip adds to "
        "the combined slip and F_combined grows with α), so that statement holds only at "
        "larger slips. Increase with load at α = 10°: "
        f"{'confirmed at every slip' if load_inc else 'not at every slip'}."
    )
    return FigureResult(
        fig,
        cols,
        rows,
        comparison,
        verdict="F_pure ≥ F_combined and growth with load confirmed; "
        f"'F_combined decreases with α' only for slip ≥ {first_dec:.2f}",
    )


@figure(
    "3.14",
    "force direction β vs slip",
    "Direction of the pure and combined resultant forces vs slip at α = 10° for "
    "3.5, 5, 7.5 kN (assumed).",
    ("3.8", "3.11", "3.12", "3.14", "3.15"),
)
def fig_3_14(ctx):
    slips = np.linspace(0.0, 1.0, ctx.n_curve)
    loads = np.array(TIRE_LOADS)
    f = tire_forces(loads[:, None], slips[None, :], math.radians(SLIP_ANGLE_DEG))
    bp, bc = np.degrees(np.asarray(f.beta_pure)), np.degrees(np.asarray(f.beta_combined))
    fig, ax = subplots(figsize=(6.4, 4.4))
    for k, load in enumerate(loads):
        ax.plot(slips[1:], bp[k, 1:], "-", color=f"C{k}", label=f"β_pure, {load / 1e3:g} kN")
        ax.plot(slips[1:], bc[k, 1:], "--", color=f"C{k}", label=f"β_combined, {load / 1e3:g} kN")
    ax.axhline(45, color="grey", lw=0.8)
    ax.set_xlabel("driving slip i [-]")
    ax.set_ylabel("force direction β [deg]")
    thesis_title(ax, "3.14", f"force direction vs slip, α = {SLIP_ANGLE_DEG:g}°")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    rows = [[s] + list(bp[:, j]) + list(bc[:, j]) for j, s in enumerate(slips)]
    cols = (
        ["slip"]
        + [f"beta_pure_{l / 1e3:g}kN_deg" for l in loads]
        + [f"beta_combined_{l / 1e3:g}kN_deg" for l in loads]
    )
    j = 1
    mid = lambda b: float(np.interp(45.0, b[::-1], slips[::-1]))  # b decreasing in slip
    load_c = np.ptp(bc[:, 1:], axis=0).max()  # spread over the loads
    load_p = np.ptp(bp[:, 1:], axis=0).max()
    comparison = (
        "Thesis (3.4.2): at small slips both directions are close to 90° (lateral force "
        "dominates), at intermediate slips close to 45°, at full slip close to 0°, and the "
        f"load has no influence. The slip angle is not given; we use α = {SLIP_ANGLE_DEG:g}°. "
        f"At slip {slips[j]:.2f}: β_pure = {bp[1, j]:.1f}°, β_combined = {bc[1, j]:.1f}° "
        f"(5 kN). β_combined crosses 45° at slip {mid(bc[1]):.3f}, β_pure at "
        f"{mid(bp[1]) if bp[1].min() < 45 else float('nan'):.3f}. At slip 1 β_combined = "
        f"{bc[1, -1]:.1f}° (the lateral slip (3.8) vanishes with 1 − i), but β_pure = "
        f"{bp[1, -1]:.1f}°: the pure lateral force (3.12) does not depend on slip, so β_pure "
        "does not go to zero — the thesis's statement holds for the combined force only. "
        f"Load influence over 3.5–7.5 kN: β_combined varies by ≤ {load_c:.2f}°, "
        f"β_pure by ≤ {load_p:.2f}° (small, but not nil)."
    )
    return FigureResult(
        fig,
        cols,
        rows,
        comparison,
        verdict=f"β_combined 90° → 45° (slip {mid(bc[1]):.2f}) → 0° confirmed; "
        f"β_pure ends at {bp[1, -1]:.0f}°, not 0°; load effect small",
    )


@figure(
    "3.15",
    "force direction β vs slip angle",
    "Direction of the pure and combined resultant forces vs slip angle 0–30° at "
    "5 kN for slips 0.05, 0.2, 0.5, 0.9 (assumed).",
    ("3.8", "3.11", "3.12", "3.14", "3.15"),
)
def fig_3_15(ctx):
    alphas = np.linspace(0.0, 30.0, ctx.n_curve)
    slips = np.array([0.05, 0.2, 0.5, 0.9])
    f = tire_forces(5000.0, slips[:, None], np.radians(alphas)[None, :])
    bp, bc = np.degrees(np.asarray(f.beta_pure)), np.degrees(np.asarray(f.beta_combined))
    fig, ax = subplots(figsize=(8.4, 4.4))
    for k, s in enumerate(slips):
        ax.plot(alphas, bp[k], "-", color=f"C{k}", label=f"β_pure, i = {s:g}")
        ax.plot(alphas, bc[k], "--", color=f"C{k}", label=f"β_combined, i = {s:g}")
    ax.set_xlabel("slip angle α [deg]")
    ax.set_ylabel("force direction β [deg]")
    thesis_title(ax, "3.15", "force direction vs slip angle, 5 kN")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    rows = [[a] + list(bp[:, j]) + list(bc[:, j]) for j, a in enumerate(alphas)]
    cols = (
        ["alpha_deg"]
        + [f"beta_pure_i{s:g}_deg" for s in slips]
        + [f"beta_combined_i{s:g}_deg" for s in slips]
    )
    monotone = bool(np.all(np.diff(bp, axis=1) >= -1e-9) and np.all(np.diff(bc, axis=1) >= -1e-9))
    comparison = (
        "The thesis shows the orientation of the pure and combined forces against slip "
        "angle without further comment (section 3.4.2). Load and slips are not given; we "
        "use 5 kN and slips 0.05, 0.2, 0.5, 0.9. Both directions grow monotonically from 0° "
        "at α = 0 "
        f"(monotone: {monotone}); "
        f"at α = 30° β_combined = {', '.join(f'{x:.1f}' for x in bc[:, -1])}° and β_pure = "
        f"{', '.join(f'{x:.1f}' for x in bp[:, -1])}° for the four slips. The combined force "
        "turns towards the lateral direction faster at small slip; at i = 0.9 β_combined "
        "stays far below β_pure, because the (1 − i) factor of (3.8) shrinks the lateral "
        "slip while the pure lateral force (3.12) ignores the slip."
    )
    return FigureResult(
        fig,
        cols,
        rows,
        comparison,
        verdict="no claim in the thesis to check; both directions rise monotonically with α",
    )


@figure(
    "3.16",
    "isotropic vs anisotropic friction",
    "Pure and combined forces and their directions for the thesis tyre "
    "(anisotropic, μ_x ≠ μ_y from 3.19, 3.20) and an isotropic variant with "
    "μ_y = μ_x (assumed), at α = 10° and 3.5 / 7.5 kN.",
    ("3.13", "3.14", "3.15", "3.16", "3.19", "3.20"),
)
def fig_3_16(ctx):
    slips = np.linspace(0.0, 1.0, ctx.n_curve)
    loads = np.array([3500.0, 7500.0])
    alpha = math.radians(SLIP_ANGLE_DEG)
    p = tire_parameters(loads[:, None])
    iso = TireParameters(c_s=p.c_s, c_alpha=p.c_alpha, mu_x=p.mu_x, mu_y=p.mu_x, e1=p.e1)
    fa = tire_forces_from_parameters(loads[:, None], slips[None, :], alpha, p)
    fi = tire_forces_from_parameters(loads[:, None], slips[None, :], alpha, iso)
    fig, (ax1, ax2) = subplots(1, 2, figsize=(11, 4.4))
    for k, load in enumerate(loads):
        for f, name, ls in ((fa, "anisotropic", "-"), (fi, "isotropic", "--")):
            ax1.plot(
                slips,
                np.asarray(f.pure[k]),
                ls,
                color=f"C{2 * k}",
                label=f"F_pure, {name}, {load / 1e3:g} kN",
            )
            ax1.plot(
                slips,
                np.asarray(f.combined[k]),
                ls,
                color=f"C{2 * k + 1}",
                label=f"F_combined, {name}, {load / 1e3:g} kN",
            )
            ax2.plot(
                slips[1:],
                np.degrees(np.asarray(f.beta_combined[k]))[1:],
                ls,
                color=f"C{2 * k + 1}",
                label=f"β_combined, {name}, {load / 1e3:g} kN",
            )
            ax2.plot(
                slips[1:],
                np.degrees(np.asarray(f.beta_pure[k]))[1:],
                ls,
                color=f"C{2 * k}",
                lw=0.8,
                label=f"β_pure, {name}, {load / 1e3:g} kN",
            )
    ax1.set_ylabel("|F| [N]")
    ax2.set_ylabel("force direction β [deg]")
    for ax, loc in ((ax1, "lower right"), (ax2, "upper right")):
        ax.set_xlabel("driving slip i [-]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6, ncol=2, loc=loc)
    ax1.set_title("(a) force magnitudes", fontsize=9)
    ax2.set_title("(b) force directions", fontsize=9)
    fig.suptitle(
        f"Fig. 3.16 (cf. thesis): isotropic (μ_y = μ_x) vs anisotropic friction, "
        f"α = {SLIP_ANGLE_DEG:g}°",
        fontsize=10,
    )
    fig.tight_layout()
    rows = [
        [
            s,
            float(fa.pure[0, j]),
            float(fa.combined[0, j]),
            float(fi.pure[0, j]),
            float(fi.combined[0, j]),
            math.degrees(float(fa.beta_combined[0, j])),
            math.degrees(float(fi.beta_combined[0, j])),
        ]
        for j, s in enumerate(slips)
    ]
    cols = [
        "slip",
        "F_pure_aniso_3.5kN_N",
        "F_comb_aniso_3.5kN_N",
        "F_pure_iso_3.5kN_N",
        "F_comb_iso_3.5kN_N",
        "beta_comb_aniso_3.5kN_deg",
        "beta_comb_iso_3.5kN_deg",
    ]
    d_mu = np.degrees(np.abs(np.asarray(fa.beta_combined) - np.asarray(fi.beta_combined)))[
        :, 1:
    ].max()
    d_load = np.degrees(np.ptp(np.asarray(fa.beta_combined), axis=0))[1:].max()
    d_pure = np.degrees(np.abs(np.asarray(fa.beta_pure) - np.asarray(fi.beta_pure)))[:, 1:].max()
    ge = bool(np.all(np.asarray(fi.pure) - np.asarray(fi.combined) >= -1e-9))
    comparison = (
        "Thesis (3.4.3): for both the isotropic (μ_x = μ_y) and anisotropic cases "
        "β_combined is independent of the friction coefficient and of the normal load. "
        "The thesis does not say which μ the isotropic case uses; we set μ_y = μ_x(F_z) "
        "(3.19) and keep the rest. Independence of μ is exact here: max |Δβ_combined| = "
        f"{d_mu:.2g}° between the two cases (tan β = C_α(1 − i) tan α / (C_s i), no μ), "
        f"whereas β_pure changes by up to {d_pure:.1f}°. Independence of the load is "
        f"approximate: β_combined differs by ≤ {d_load:.2f}° between 3.5 and 7.5 kN "
        "(through C_α/C_s). The isotropic tyre has the larger lateral force and "
        f"F_pure ≥ F_combined still holds ({ge})."
    )
    return FigureResult(
        fig,
        cols,
        rows,
        comparison,
        verdict=f"confirmed: β_combined independent of μ (|Δβ| = {d_mu:.1g}°) "
        f"and nearly of load (≤ {d_load:.2f}°)",
    )
