"""Independent NumPy/SciPy reference for the rigid wheel on Wong snow (thesis chapter 4).

Written directly from the thesis's equations with adaptive quadrature (`scipy.integrate.quad`)
and `scipy.optimize.brentq`; it shares no code with snowjax.  The integration interval is
split where the integrands are hard for quad: geometrically towards theta = 0 (the log
singularity of Wong's law when the wheel nears the base), at sign changes of the shear
mobilisation (braking), and towards the entry angle (the shear layer).
"""

import math

import numpy as np
from scipy import integrate, optimize


def sigma(theta, theta0, D, p_w, z_w):
    """Wong's law (4.1b) on the rim (4.5)."""
    z = D / 2 * (math.cos(theta) - math.cos(theta0))
    return -p_w * math.log1p(-z / z_w)


def mobilisation_arg(theta, theta0, slip, D, p_w, z_w, c, tan_phi, K, shear):
    """j/K (4.10, 4.11) or U0 (4.13)."""
    if shear == "classic":
        j = D / 2 * ((theta0 - theta) - (1 - slip) * (math.sin(theta0) - math.sin(theta)))
        return j / K
    s_bar = sigma(theta, theta0, D, p_w, z_w) / c
    tau1 = (D / K) * (z_w / D) * (c / p_w) * math.cos(theta0) / math.sin(theta0)
    tau2 = 1 / math.cos(theta0) - 1
    return (slip + tau2) * tau1 * s_bar + (2 * slip - slip**2) * tau1 * s_bar**3 / 6


def tau(theta, theta0, slip, D, p_w, z_w, c, tan_phi, K, shear):
    if shear == "none":
        return 0.0
    x = mobilisation_arg(theta, theta0, slip, D, p_w, z_w, c, tan_phi, K, shear)
    g = math.copysign(-math.expm1(-abs(x)), x)  # mirrored Janosi-Hanamoto for x < 0
    return (c + sigma(theta, theta0, D, p_w, z_w) * tan_phi) * g


def _breakpoints(theta0, slip, D, p_w, z_w, c, tan_phi, K, shear):
    a = D / (2 * z_w)
    z0_rel = max(1 - a * (1 - math.cos(theta0)), 0.0)
    pts = {0.0, theta0}
    e = max(math.sqrt(2 * z0_rel / a), 1e-12)
    while e < theta0:
        pts.add(e)
        e *= 4
    if shear != "none":
        grid = np.linspace(0, theta0, 801)[1:-1]
        vals = [mobilisation_arg(t, theta0, slip, D, p_w, z_w, c, tan_phi, K, shear) for t in grid]
        f = lambda t: mobilisation_arg(t, theta0, slip, D, p_w, z_w, c, tan_phi, K, shear)
        for k in range(len(grid) - 1):
            if vals[k] * vals[k + 1] < 0:
                root = optimize.brentq(f, grid[k], grid[k + 1], xtol=1e-15)
                pts.add(root)
                for m in (1, 4, 16):
                    width = K / D * m
                    pts.update(p for p in (root - width, root + width) if 0 < p < theta0)
        slope = abs(1 - (1 - slip) * math.cos(theta0)) * D / 2
        for m in (1, 4, 16, 64):
            p = theta0 - m * K / max(slope, 1e-12)
            if p > 0:
                pts.add(p)
    return sorted(pts)


def contact_integrals(theta0, slip, D, b, p_w, z_w, c, tan_phi, K, shear):
    """(W, R, T, M): eq. (4.14), (4.16), (2.9)*r*b, (2.12), by adaptive quadrature."""
    args = (theta0, slip, D, p_w, z_w, c, tan_phi, K, shear)
    sig = lambda t: sigma(t, theta0, D, p_w, z_w)
    ta = lambda t: tau(t, *args[:1], slip, D, p_w, z_w, c, tan_phi, K, shear)
    fns = [
        lambda t: sig(t) * math.cos(t) + ta(t) * math.sin(t),
        lambda t: sig(t) * math.sin(t),
        lambda t: ta(t) * math.cos(t),
        ta,
    ]
    pts = _breakpoints(*args)
    out = []
    for f in fns:
        total = 0.0
        for lo, hi in zip(pts[:-1], pts[1:]):
            total += integrate.quad(f, lo, hi, epsabs=0.0, epsrel=1e-13, limit=200)[0]
        out.append(total)
    r = D / 2
    w, rr, t, m = out
    return np.array([w * r * b, rr * r * b, t * r * b, m * r * r * b])


def solve(load, slip, D, b, p_w, z_w, c, tan_phi, K, shear):
    """theta0 with W(theta0) = load by brentq, and the forces there (None if bottomed)."""
    theta_max = math.acos(1 - 2 * z_w / D)
    W = lambda th: contact_integrals(th, slip, D, b, p_w, z_w, c, tan_phi, K, shear)[0] - load
    if W(theta_max * (1 - 1e-13)) < 0:
        return None
    theta0 = optimize.brentq(W, 1e-6, theta_max * (1 - 1e-13), xtol=1e-15, rtol=1e-14)
    return theta0, contact_integrals(theta0, slip, D, b, p_w, z_w, c, tan_phi, K, shear)
