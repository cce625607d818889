"""Random wheel/snow cases over `solve_wheel`'s documented range (WongSnow, front region).

D 0.5-1.5 m, b 0.1-0.6 m, p_w 5-200 kPa, z_w 5-35 cm and below 0.45 D, cohesion
0.1-20 kPa, tan phi 0.02-0.8, K 2-80 mm, load 0.1-20 kN (log-uniform where the range
spans decades), slip in the given interval.
"""

from __future__ import annotations

import numpy as np

import snowjax as sj


def in_range(n: int, seed: int = 0, slip=(-0.5, 0.99), dtype=np.float64):
    """(wheel, snow, load [N], slip [-]) with n random in-range elements of `dtype`."""
    rng = np.random.default_rng(seed)
    log_uniform = lambda lo, hi: np.exp(rng.uniform(np.log(lo), np.log(hi), n))  # noqa: E731
    d = rng.uniform(0.5, 1.5, n)
    b = rng.uniform(0.1, 0.6, n)
    p_w = log_uniform(5e3, 200e3)
    z_w = rng.uniform(0.05, np.minimum(0.35, 0.45 * d))
    c = log_uniform(100.0, 20e3)
    tan_phi = rng.uniform(0.02, 0.8, n)
    k = log_uniform(0.002, 0.08)
    load = log_uniform(100.0, 20e3)
    i = rng.uniform(slip[0], slip[1], n)
    cast = lambda x: np.asarray(x, dtype)  # noqa: E731
    wheel = sj.RigidWheel(cast(d), cast(b))
    snow = sj.WongSnow(cast(p_w), cast(z_w), cast(c), cast(tan_phi), cast(k))
    return wheel, snow, cast(load), cast(i)
