"""Values taken from (or derived from) the thesis and shared by several models; SI units."""

from __future__ import annotations

from importlib.metadata import version

# The installed distribution's version (pyproject.toml).
VERSION = version("snowjax")

# The thesis does not give p_w.  Table 4.1 lists an entry angle of 53.6747 deg, which is
# exactly a sinkage z0 = D/2 (1 - cos theta0) = 0.1500 m = 0.75 z_w.  We take that state
# as the no-shear equilibrium (eq. 4.14 with tau = 0) at F_z = 5 kN, the middle of the
# thesis's FEA load range 3.5-7.5 kN (section 3.2), with the 0.235 m wide tyre below:
# p_w = F_z / (r b int_0^theta0 -ln(Z) cos(theta) dtheta) = 85.55 kPa (computed once with
# scipy.integrate.quad; tests/test_params.py re-derives it).
THESIS_P_W = 85_549.0  # [Pa]

# Wong's own rule (section 2.1.2: p_w is a third of the pressure at z = 0.95 z_w) applied
# to the thesis's plate data (Table 2.1, rows 17-18: 36.96 kPa at 0.1865 m, 39.54 kPa at
# 0.1915 m; 38.77 kPa at 0.95 z_w = 0.190 m).
PLATE_RULE_P_W = 38_770.0 / 3.0  # [Pa] = 12.92 kPa

# Section width of the P235/75R15 tyre whose nominal diameter (0.734 m) matches the
# thesis's D = 0.736 m; the thesis does not state the width used.
THESIS_TIRE_WIDTH = 0.235  # [m]

THESIS_DIAMETER = 0.736  # [m]

# Shear deformation modulus used where a published parameter set gives none: the thesis's
# fresh snow, Table 4.1 (u_k = D / K = 73.6 with D = 0.736 m, so K = 10 mm).
DEFAULT_SHEAR_MODULUS = 0.736 / 73.6  # [m]
