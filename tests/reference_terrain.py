"""Independent SciPy reference for the rigid wheel on any terrain law and distribution.

Written from the equations (Bekker 2.1, Reece 2.4, Wong 2.3, the layered law of
`LayeredSnow`, the Wong–Reece 1967 distribution, Janosi–Hanamoto 4.11 on the shear
displacement 4.10) with `scipy.integrate.quad` and `scipy.optimize.brentq`; it shares
no code with snowjax.  The interval is cut wherever an integrand has a kink or a jump
(theta_m, the sign change of the shear displacement, the ice layer's failure angles)
and geometrically towards the entry angle (the shear layer) and the exit angle.
"""

import math

import numpy as np
from scipy import integrate, optimize


def bekker(n, k_c, k_phi):
    return lambda z, b: (k_c / b + k_phi) * max(z, 0.0) ** n


def reece(n, k_c_prime, k_phi_prime, gamma, c):
    return lambda z, b: (c * k_c_prime + gamma * b * k_phi_prime) * (max(z, 0.0) / b) ** n


def wong(p_w, z_w):
    return lambda z, b: -p_w * math.log1p(-max(z, 0.0) / z_w)


def layered(p1, zw1, p2, zw2, p_fail):
    z_f = -zw1 * math.expm1(-p_fail / p1)

    def law(z, b):
        z = max(z, 0.0)
        return -p1 * math.log1p(-z / zw1) if z < z_f else -p2 * math.log1p(-z / zw2)

    return law, z_f


def contact(
    theta0,
    slip,
    D,
    b,
    law,
    c,
    tan_phi,
    K,
    fm=0.0,
    fr=0.0,
    shear="classic",
    z_f=None,
    lower=None,
    mobilisation=None,
    epsrel=1e-13,
    vertical_only=False,
):
    """(W, R, T, M) by adaptive quadrature over theta_r .. theta0 (relative tolerance
    `epsrel`); the array (W,) alone if `vertical_only`.

    `lower` = (c, tan_phi, K) of the layer below the ice, used past the failure sinkage.
    `mobilisation(x)`: the factor g(j / K) of tau = (c + sigma tan phi) g (default the
    mirrored Janosi–Hanamoto `sign(x) (1 - exp(-|x|))`).
    """
    r = D / 2
    tm, tr = fm * theta0, fr * theta0

    def theta_eff(th):
        if th >= tm or tm == tr:
            return th
        return theta0 - (th - tr) / (tm - tr) * (theta0 - tm)

    def sig(th):
        te = theta_eff(th)
        return law(r * (math.cos(te) - math.cos(theta0)), b)

    def tau(th):
        if shear == "none":
            return 0.0
        j = r * ((theta0 - th) - (1 - slip) * (math.sin(theta0) - math.sin(th)))
        c_, tp_, k_ = c, tan_phi, K
        if lower is not None and r * (math.cos(theta_eff(th)) - math.cos(theta0)) >= z_f:
            c_, tp_, k_ = lower
        x = j / k_
        if mobilisation is not None:
            return (c_ + sig(th) * tp_) * mobilisation(x)
        return (c_ + sig(th) * tp_) * math.copysign(-math.expm1(-abs(x)), x)

    pts = {tr, tm, theta0}
    for m in (1, 4, 16, 64, 256):
        for p in (theta0 - m * K / r, tr + (theta0 - tr) / 4**m):
            if tr < p < theta0:
                pts.add(p)
    if shear != "none":
        f = lambda th: (theta0 - th) - (1 - slip) * (math.sin(theta0) - math.sin(th))  # noqa: E731
        grid = np.linspace(tr, theta0, 2001)[1:-1]
        vals = [f(t) for t in grid]
        for k in range(len(grid) - 1):
            if vals[k] * vals[k + 1] < 0:
                root = optimize.brentq(f, grid[k], grid[k + 1], xtol=1e-15)
                pts.add(root)
                for m in (1, 4, 16):
                    pts.update(p for p in (root - m * K / r, root + m * K / r) if tr < p < theta0)
    if z_f is not None:
        cf = math.cos(theta0) + z_f / r
        if cf < 1:
            th_f = math.acos(cf)
            pts.add(th_f)
            if tm > tr and th_f > tm:
                pts.add(tr + (theta0 - th_f) / (theta0 - tm) * (tm - tr))
    pts = sorted(p for p in pts if tr <= p <= theta0)
    fns = [
        lambda t: sig(t) * math.cos(t) + tau(t) * math.sin(t),
        lambda t: sig(t) * math.sin(t),
        lambda t: tau(t) * math.cos(t),
        tau,
    ]
    out = []
    for fn in fns[:1] if vertical_only else fns:
        total = 0.0
        for lo, hi in zip(pts[:-1], pts[1:]):
            if hi > lo:
                total += integrate.quad(fn, lo, hi, epsabs=0.0, epsrel=epsrel, limit=400)[0]
        out.append(total)
    if vertical_only:
        return np.array([out[0] * r * b])
    w, rr, t, m = out
    return np.array([w * r * b, rr * r * b, t * r * b, m * r * r * b])


def solve(load, slip, D, b, law, c, tan_phi, K, *args, depth=math.inf, shallowest=False, **kw):
    """theta0 with W(theta0) = load by brentq (the shallowest root if `shallowest`).

    theta0 is searched up to 85 degrees, or up to the base at `depth` [m] if shallower;
    `args` and `kw` are the rest of `contact`'s arguments (fm, fr, shear, z_f, lower,
    mobilisation).
    """
    theta_max = math.radians(85.0)
    if 2 * depth / D < 2:
        theta_max = min(theta_max, math.acos(1 - 2 * depth / D))
    args = (D, b, law, c, tan_phi, K, *args)
    W = lambda th: contact(th, slip, *args, **kw, vertical_only=True)[0] - load  # noqa: E731
    lo, hi = 1e-4, theta_max * (1 - 1e-12)
    if shallowest:
        # The first grid point past the load, W alone at a loose tolerance (only its sign
        # is used; brentq below raises if the bracket were wrong).
        scan = lambda th: contact(th, slip, *args, **kw, epsrel=1e-5, vertical_only=True)[0]  # noqa: E731
        grid = np.linspace(lo, hi, 1000)
        k = next(i for i, t in enumerate(grid) if scan(t) >= load)
        lo, hi = grid[k - 1], grid[k]
    theta0 = optimize.brentq(W, lo, hi, xtol=1e-15, rtol=1e-14)
    return theta0, contact(theta0, slip, *args, **kw)
