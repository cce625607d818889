"""Independent SciPy reference for the deflecting tyre (`snowjax.DeflectingTire`).

Written from the model's equations (Bekker 1969 / Wong, *Theory of Ground Vehicles*,
section 2.5: a flat of pressure p_f at the sinkage where the terrain's law reaches it,
a chord of the undeflected circle, carrying p_f under every distribution; the smooth
switch of `snowjax._wheel.tire`), with
`scipy.integrate.quad` and `scipy.optimize.brentq`; it shares no code with snowjax.  The
flat is integrated in its own coordinate x (not as a part of the rim), the curved
regions in theta; the law is inverted by brentq, not by a closed form.

`law(z, b)` is a pressure–sinkage law as in `reference_terrain` (Bekker, Wong).
Front region (fm = fr = 0) or Wong–Reece (theta_m = fm theta0, theta_r = fr theta0),
Janosi–Hanamoto shear on the shear displacement of the tread (its travel from the
entry less the ground's, (1 - i) times the horizontal distance).
"""

import math

import numpy as np
from scipy import integrate, optimize


def flat(theta0, D, b, law, p_cap, m):
    """(z_f, delta, theta_f, p_f): the flat's sinkage, the deflection, the flat's
    half-angle and its pressure."""
    s = D / 2 * (1 - math.cos(theta0))
    rim = law(s, b)
    log_rim = math.log(rim) if rim > 0 else -math.inf
    gap = math.log(p_cap) - log_rim
    p_f = math.exp(math.log(p_cap) - np.logaddexp(0.0, m * gap) / m)
    if p_f >= rim:
        z_f = s
    else:
        z_f = optimize.brentq(lambda z: law(z, b) - p_f, 0.0, s, xtol=1e-17, rtol=1e-15)
    delta = s - z_f
    return z_f, delta, 2 * math.asin(math.sqrt(max(delta, 0.0) / D)), p_f


def contact(theta0, slip, D, b, law, c, tan_phi, K, p_cap, m, fm=0.0, fr=0.0):
    """(W, R, T, M) of the deflecting tyre at entry angle theta0, by adaptive quadrature."""
    r = D / 2
    z_f, delta, th_f, p_f = flat(theta0, D, b, law, p_cap, m)
    x_f = r * math.sin(th_f)  # the flat spans -x_f..x_f
    tm, tr = fm * theta0, fr * theta0
    x_r = max(r * math.sin(tr), -x_f)  # the flat's rear end inside the contact

    def theta_eff(th):
        if th >= tm or tm == tr:
            return th
        return theta0 - (th - tr) / (tm - tr) * (theta0 - tm)

    def depth(th):
        return min(r * (math.cos(theta_eff(th)) - math.cos(theta0)), z_f)

    def travel(th):
        """Arc length of the tread from the entry to the rim angle th (arcs) [m]."""
        if th >= th_f:
            return r * (theta0 - th)
        return r * (theta0 - th_f) + 2 * x_f + r * (-th_f - th)

    def tau(sig, j):
        return (c + sig * tan_phi) * math.copysign(-math.expm1(-abs(j) / K), j)

    def arc(th):  # per d theta: (W, R, T, M)
        sig = law(depth(th), b)
        j = travel(th) - (1 - slip) * r * (math.sin(theta0) - math.sin(th))
        t = tau(sig, j)
        cs, sn = math.cos(th), math.sin(th)
        return np.array([sig * cs + t * sn, sig * sn, t * cs, t * r]) * r

    def on_flat(x):  # per dx: (W, R, T, M); the flat carries p_f (elastic mode)
        sig = p_f
        j = r * (theta0 - th_f) + (x_f - x) - (1 - slip) * r * (math.sin(theta0) - x / r)
        t = tau(sig, j)
        return np.array([sig, 0.0, t, t * (r - delta) + sig * x])

    def integrate_pieces(fn, points):
        total = np.zeros(4)
        for lo, hi in zip(points[:-1], points[1:]):
            if hi > lo:
                for k in range(4):
                    total[k] += integrate.quad(
                        lambda v, k=k: fn(v)[k], lo, hi, epsabs=0.0, epsrel=1e-13, limit=400
                    )[0]
        return total

    def cuts(lo, hi, extra):
        pts = {lo, hi, *extra}
        for k in (1, 4, 16, 64, 256):
            pts.update((theta0 - k * K / r, lo + (hi - lo) / 4**k))
        return sorted(p for p in pts if lo <= p <= hi)

    # Sign changes of j (braking) on the arcs and the flat: grid + brentq.
    def j_of_theta(th):
        if abs(th) < th_f:
            x = r * math.sin(th)
            return r * (theta0 - th_f) + (x_f - x) - (1 - slip) * r * (math.sin(theta0) - x / r)
        return travel(th) - (1 - slip) * r * (math.sin(theta0) - math.sin(th))

    roots = []
    grid = np.linspace(tr, theta0, 4001)[1:-1]
    vals = [j_of_theta(t) for t in grid]
    for k in range(len(grid) - 1):
        if vals[k] * vals[k + 1] < 0:
            roots.append(optimize.brentq(j_of_theta, grid[k], grid[k + 1], xtol=1e-15))
    near = [p for root in roots for k in (1, 4, 16) for p in (root - k * K / r, root + k * K / r)]
    extra = [tm, *roots, *near]
    if tm > tr and th_f > tm:  # the rear angle whose stress angle is the flat's end
        extra.append(tr + (theta0 - th_f) / (theta0 - tm) * (tm - tr))
    total = integrate_pieces(arc, cuts(th_f, theta0, extra))
    if tr < -th_f:
        total += integrate_pieces(arc, cuts(tr, -th_f, extra))
    flat_cuts = {x_r, x_f, *(r * math.sin(p) for p in extra if abs(p) < th_f)}
    total += integrate_pieces(on_flat, sorted(p for p in flat_cuts if x_r <= p <= x_f))
    return total * b


def solve(load, slip, D, b, law, c, tan_phi, K, p_cap, m, fm=0.0, fr=0.0, theta_max=None):
    """theta0 with W(theta0) = load by brentq, and (W, R, T, M) there."""
    theta_max = math.radians(85.0) if theta_max is None else theta_max
    args = (D, b, law, c, tan_phi, K, p_cap, m, fm, fr)
    theta0 = optimize.brentq(
        lambda th: contact(th, slip, *args)[0] - load, 1e-3, theta_max, xtol=1e-15, rtol=1e-14
    )
    return theta0, contact(theta0, slip, *args)
