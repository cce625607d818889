"""A pneumatic tyre whose tread flattens where the ground would press harder than the tyre
can carry: Bekker's and Wong's rigid / elastic modes of a flexible tyre on soft ground,
with a smooth switch between them.

Model (Bekker, *Introduction to Terrain-Vehicle Systems*, 1969, ch. 5; Wong, *Theory of
Ground Vehicles*, 4th ed. 2008, section 2.5 "Motion resistance of a tyre"): a tyre of
inflation pressure p_i whose carcass adds a pressure p_c carries at most
p_i + p_c on its contact.  If the terrain, loaded by a rigid rim of the tyre's diameter,
would press on the lowest point of the rim with less than that (the "critical ground
pressure" p_gcr < p_i + p_c), the tyre runs like a rigid rim (rigid mode).  Otherwise
its bottom flattens (elastic mode): a flat section at the sinkage z_f where the
terrain's own law reaches p_i + p_c, sigma(z_f) = p_i + p_c, joined to the curved
entry (and, with a rear distribution, exit) regions of the undeflected circle.  The
flat is a chord of the undeflected circle of diameter D, at the deflection delta above
the circle's lowest point; its half-angle theta_f has cos(theta_f) = 1 - 2 delta / D.

The solver's unknown stays the entry angle theta0 of the undeflected circle, whose
lowest point lies at s = D sin^2(theta0 / 2) below the surface.  Where this model
departs from the books: the switch is smooth.  In the books the flat's pressure is
p_f = min(sigma(s), p_i + p_c), which makes the sinkage, and with it the motion
resistance, a function of the load with a kink at the mode boundary (in the elastic
mode the sinkage no longer grows with the load).  Here

    ln p_f = ln(p_i + p_c) - softplus(m [ln(p_i + p_c) - ln sigma(s)]) / m,

a smooth minimum in log-pressure of sharpness m (`sharpness`, default 30: at
sigma(s) = p_i + p_c the flat carries 2^(-1/m) = 0.977 of p_i + p_c; at half of it, the
rigid rim's pressure is reduced by 0.5^m / m = 3e-11 relative; where sigma(s) is 1.4
times p_i + p_c the flat carries p_i + p_c within 1.4e-6).  z_f = sigma^(-1)(p_f) (the
terrain's `sinkage_at_pressure`) and delta = s - z_f follow, so every output is smooth
(C-infinity) in the load, the pressures and every snow parameter, and the books' model
is the limit m -> infinity.  As p_i -> infinity, p_f -> sigma(s) and the tyre is the
rigid rim of the same diameter and width.

On the flat the normal stress is p_f itself, under every stress distribution (a
Wong–Reece rear region's mapped stresses act on the curved exit; a point whose stress
angle lies on the flat carries p_f too), vertical, and the shear stress horizontal; the
shear displacement grows along it as i x (the tread moves along the flat at the speed of the
undeflected circumference, omega r, as in Wong's treatment of the flat), so (4.10)
becomes j = (arc length of the tread from the entry) - (1 - i)(x_entry - x).  The
normal stress on the flat has a moment about the axle (arm x) and the shear stress
acts at the flat's distance r - delta below the axle.

Flexing resistance.  Bekker (1969) and Wong (section 2.5) split a tyre's motion
resistance on soft ground into the terrain's compaction (the stress integrals above)
and the flexing (hysteresis) of the carcass, and take the latter from measurements of
the tyre on a hard surface.  Here: a tyre whose rolling-resistance coefficient on a hard
surface is f_h (`hard_surface_resistance`, default 0) loses, at the deflection delta it
has on the soft ground, what it loses on a hard surface at that deflection,

    R_f = f_h W_h(delta),    W_h(delta) = p_f b l,    l = 2 sqrt(delta (D - delta)),

W_h the load that gives the deflection delta on a hard surface in this same model: the
flat, of length l (= D sin theta_f, `flat_length`), carrying p_f (= p_i + p_c in the
elastic mode).  Two assumptions are this package's, not the books': f_h does not change
with the load, and the losses are equal at equal deflection.  R_f is added to the motion
resistance R, so the drawbar pull is thrust - compaction - flexing (Wong's accounting);
the vertical equilibrium and the torque are unchanged.  Measured snow resistances are
often given net of the hard-surface rolling resistance (e.g. Shoop 2001, Table 11: "only
the portion of the resistance due to the deformation of the terrain"); compare those
with f_h = 0.

Two numerical choices keep R_f smooth and vanishing in the rigid mode.  Deep in the
rigid mode delta is a rounding error of s - z_f, while its derivative is not: l is
computed as 2 delta sqrt((D - delta) / (delta + delta_0)), delta_0 = 1e-9 D, linear in
delta below delta_0 (so a rounding error stays one, and the slope is right) and within
delta_0 / (2 delta) of the chord above it (4e-7 relative at 1 mm).  And W_h uses p_f,
not p_i + p_c: with p_i -> infinity the latter would multiply that rounding error.

At a base and on a law that drops.  On a law with a base (Wong snow) the undeflected
circle may pass the base by the section height, the flat staying above it, where the
law reaches p_f; but a tyre whose p_i + p_c reaches the law's pressure `BASE_CLEARANCE`
(1e-12) z_w above the base rests on the base like a rigid rim (its circle stops there,
`Status.BOTTOMED_OUT`): the snow under its flat has nothing left to give, and without
this a stiff tyre would carry the load a rim leaves to the base on snow within a
rounding error of it.  On a law that drops where it breaks (`LayeredSnow`'s ice layer;
`AbstractTerrain.pressure_rises` False) the tyre cannot press through a piece of the law
that reaches more than p_i + p_c: the flat lies in the first such piece, else in the one
holding s (`DeflectingTire._flat_on_pieces`); so a tyre softer than the ice rides on it
and a stiff one breaks it where the rim does, and across that threshold the flat jumps.

Not modelled: sidewall contact with the snow, and the tyre's growth of contact width
with deflection (the width stays the section width b).  A deflection beyond the section
height (the rim would reach the ground) is not flagged by a status; compare
`deflection` with `section_height`.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._constants import THESIS_DIAMETER, THESIS_TIRE_WIDTH
from .._leaves import _as_float, parameter
from .._terrain.base import _bisect_pressure
from .distribution import _is_front
from .geometry import (
    AbstractContact,
    AbstractWheel,
    ContactPoints,
    RigidWheel,
    Tread,
    _rim_sinkage_between,
    _shear_displacement,
    _shear_displacement_slope,
    _shear_sign_change,
    _sin_cos,
    _sincos_half,
    max_sinkage,
)

__all__ = ["DeflectingTire"]

# The clearance above a base [relative to its depth] within which a tyre's flat rests on
# the base (`DeflectingTire.deepest_reach`): the solver's closest approach of a rigid
# rim to the base (its entry angle at most theta_cap exp(-S_MIN^2), S_MIN = 1e-6).
BASE_CLEARANCE = 1e-12

# delta / s below which the deflection comes from the law's slope at s (`_flat`): the
# linearisation's relative error there is ~ delta sigma'' / (2 sigma') ~ 1e-8.
_LINEAR_DEFLECTION = 1e-8

# delta_0 / D: below this deflection the flexing resistance's sqrt(delta) turns linear
# (module docstring).
_DELTA_0 = 1e-9

# delta / s at or below which the tread counts as round (`DeflectingTire.stays_round`):
# the flat's pressure is then the rim's within ~1e-12 (relative) and the flexing
# resistance f_h p_f b l at most ~1e-7 f_h of the load (l ~ 2 delta / sqrt(delta_0 / D),
# delta <= 5e-13 D).  Measured: 6e-16 of the load between the tyre's contact and the
# rim's, f_h 0 and 0.03 (`tests/test_deflecting_tire.py`).
ROUND_DEFLECTION = 1e-12


class DeflectingTire(AbstractWheel):
    """A pneumatic tyre that runs as a rigid rim on soft ground and flattens on firm
    ground (Bekker 1969; Wong, *Theory of Ground Vehicles*, section 2.5), with a smooth
    switch between the modes (see `snowjax._wheel.tire` for the model and where it
    departs from the books).

    **Fields:**

    - `diameter`: D [m], the undeflected outer diameter.
    - `width`: b [m], the section width (the width of the contact).
    - `section_height`: h [m], from the rim seat to the tread, 0 < h < D / 2 (the
      largest deflection the carcass can take).
    - `inflation_pressure`: p_i [Pa], > 0.
    - `carcass_pressure`: p_c [Pa], >= 0: the pressure the carcass stiffness adds to
      p_i on the contact (Wong's p_c; e.g. from the tyre's hard-surface contact area A
      at load W, p_c = W / A - p_i).
    - `sharpness`: m [-], > 0, of the smooth switch between the modes (default 30).
    - `hard_surface_resistance`: f_h [-], >= 0: the tyre's coefficient of rolling
      resistance on a hard surface, for its flexing resistance R_f = f_h p_f b l, l the
      flat's length (`flat_length`; module docstring; default 0: none).

    With `inflation_pressure` large the tyre is `RigidWheel(diameter, width)` (to
    rounding, see the tests).  Every solver entry point that takes a wheel takes it;
    `WheelState.sinkage` is the flat's sinkage z_f, and `deflection(entry_angle,
    terrain)` gives delta.
    """

    diameter: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter("m", "undeflected tyre diameter D", lower=0.0, open_lower=True),
    )
    width: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter("m", "tyre section width b", lower=0.0, open_lower=True),
    )
    section_height: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter("m", "tyre section height h", lower=0.0, open_lower=True),
    )
    inflation_pressure: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter("Pa", "inflation pressure p_i", lower=0.0, open_lower=True),
    )
    carcass_pressure: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        default=0.0,
        metadata=parameter("Pa", "pressure of the carcass stiffness p_c", lower=0.0),
    )
    sharpness: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        default=30.0,
        metadata=parameter(
            "-", "sharpness m of the rigid/elastic switch", lower=0.0, open_lower=True
        ),
    )

    hard_surface_resistance: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        default=0.0,
        metadata=parameter("-", "rolling-resistance coefficient on a hard surface f_h", lower=0.0),
    )

    deflects = True
    label = "tire"

    def constraints(self) -> list[tuple[str, Array, Array, str]]:
        """The fields' ranges, and a section height below the radius."""
        ratio = self.section_height / self.diameter
        rule = ("tire.section_height / diameter", ratio, ratio < 0.5, "< 0.5 (h < D / 2)")
        return super().constraints() + [rule]

    @classmethod
    def reference(cls) -> "DeflectingTire":
        """The thesis tyre's size (P235/75R15: D 0.736 m, b 0.235 m, h 0.176 m) at 200 kPa."""
        return cls(THESIS_DIAMETER, THESIS_TIRE_WIDTH, 0.176, 200e3, 0.0)

    def flat_pressure(self, entry_angle: Float[ArrayLike, "..."], terrain) -> Float[Array, "..."]:
        """p_f [Pa]: the pressure on the flat, the smooth minimum of the rigid rim's
        lowest-point pressure sigma(s) and p_i + p_c (module docstring)."""
        return self._flat(entry_angle, terrain)[2]

    def _smooth_min(self, rim, capacity):
        """(p_f [Pa], g [-]): the smooth minimum in log-pressure of `rim` and `capacity`
        [Pa] (module docstring), and its deficit g = ln(rim / p_f) = softplus(-m x) / m,
        x = ln(capacity / rim); `rim` kept finite: 0 at the surface, +inf on a base
        (Wong's law)."""
        tiny = jnp.finfo(jnp.result_type(rim)).tiny
        log_rim = jnp.log(jnp.clip(rim, tiny, jnp.finfo(jnp.result_type(rim)).max))
        log_capacity = jnp.log(capacity)
        m = self.sharpness
        x = log_capacity - log_rim
        return jnp.exp(log_capacity - jax.nn.softplus(m * x) / m), jax.nn.softplus(-m * x) / m

    def round_rim(self) -> RigidWheel:
        """`RigidWheel(diameter, width)`: the tyre while its tread stays round."""
        return RigidWheel(self.diameter, self.width)

    def stays_round(self, entry_angle, terrain) -> Array:
        """Whether the deflection at entry angle theta0 [rad] is at most
        `ROUND_DEFLECTION` (1e-12) of the rim's sinkage: the ground presses far less
        than p_i + p_c, the tyre is its `round_rim` within the solver's accuracy."""
        sinkage = max_sinkage(entry_angle, self.diameter)
        return self.deflection(entry_angle, terrain) <= ROUND_DEFLECTION * sinkage

    def deflection(self, entry_angle: Float[ArrayLike, "..."], terrain) -> Float[Array, "..."]:
        """delta = s - z_f [m]: how far the flat lies above the undeflected circle's
        lowest point at entry angle theta0 [rad]; ~0 in the rigid mode."""
        return self._flat(entry_angle, terrain)[1]

    def _flat(self, entry_angle, terrain):
        """(z_f [m], delta [m], p_f [Pa]) at entry angle theta0.

        Deep in the rigid mode, s - z_f from the law's inverse is a rounding error of s
        (1e-17 m) that jumps from one entry angle to the next, and the flat it opens
        carries p_f where the distribution's own stress would be (Wong–Reece's lower
        one); so where the deflection is below `_LINEAR_DEFLECTION` s it comes from the
        law's slope instead, delta = (sigma(s) - p_f) / sigma'(s), with sigma(s) - p_f =
        -sigma(s) expm1(-g) from the smooth minimum's own deficit g (`_smooth_min`): exact
        to second order, and exactly 0 for a tyre far stiffer than the ground.
        """
        s = max_sinkage(entry_angle, self.diameter)
        limit = jnp.minimum(s, terrain.depth)
        capacity = self.inflation_pressure + self.carcass_pressure
        rim, slope = jax.jvp(lambda z: terrain.pressure(z, self.width), (s,), (jnp.ones_like(s),))
        if terrain.pressure_rises():
            pressure, deficit = self._smooth_min(rim, capacity)
            z_flat = type(terrain).sinkage_at_pressure(terrain, pressure, self.width, limit)
            at_rim = jnp.ones_like(s, dtype=bool)
        else:
            z_flat, pressure, deficit, at_rim = self._flat_on_pieces(s, limit, capacity, terrain)
        regular = at_rim & jnp.isfinite(rim) & (slope > 0) & jnp.isfinite(slope)
        safe_rim, safe_slope = jnp.where(regular, rim, 0.0), jnp.where(regular, slope, 1.0)
        linear = -safe_rim * jnp.expm1(-deficit) / safe_slope
        small = regular & (linear < _LINEAR_DEFLECTION * s)
        # A tyre that rests on the base never passes it (`deepest_reach`): where s
        # rounds past the base the flat would open by that rounding error.
        reach = jnp.where(self._rests_on_base(terrain), limit, s)
        delta = jnp.where(small, linear, jnp.maximum(reach - z_flat, 0.0))
        return jnp.where(small, s - linear, z_flat), delta, pressure

    def _flat_on_pieces(self, s, limit, capacity, terrain):
        """(z_f [m], p_f [Pa], its deficit g [-], whether the flat's piece is the one
        holding s) on a law that can drop where it breaks (`LayeredSnow`'s
        ice layer; `AbstractTerrain.pressure_rises` False), which rises between its
        breakpoints.

        Going down from the surface, the tyre cannot press through a piece of the law
        that reaches more than its p_i + p_c: its flat lies in the first piece whose
        largest pressure (just above the piece's lower end, where it breaks, or at the
        circle's lowest point s in the piece holding s) reaches p_i + p_c, at the smooth
        minimum of that pressure and p_i + p_c; otherwise in the piece holding s, as on
        a rising law.  So a tyre softer than the ice rides on it, and a stiff tyre
        breaks it where the rigid rim does (p_i -> infinity is the rim).  Between
        pieces the flat jumps: the ice holds or breaks.
        """
        ends = [jnp.minimum(b, limit) for b in terrain.breakpoint_sinkages()]
        ends = jnp.sort(jnp.stack(jnp.broadcast_arrays(*ends)), axis=0)
        # Each piece's deepest point: the float below its end (its derivative the end's).
        fixed = jax.lax.stop_gradient(ends)
        step = fixed - jnp.nextafter(fixed, jnp.zeros_like(fixed))
        below = ends - step
        inside = ends < limit  # the piece ending there lies above the lowest point
        rim = terrain.pressure(s, self.width)
        # Pieces: [0, e_1), [e_1, e_2), ..., [e_K, limit]; the largest pressure of each
        # is just above its end, or the lowest point's, sigma(s), in the piece holding
        # s.  The flat's piece: the first that blocks the tyre, else the one holding s.
        tops = jnp.concatenate(
            [jnp.where(inside, terrain.pressure(below, self.width), rim), rim[None]]
        )
        holding = jnp.concatenate([~inside, jnp.ones_like(inside[:1])])
        lowers = jnp.concatenate([jnp.zeros_like(ends[:1]), ends])
        uppers = jnp.concatenate([ends, limit[None]])
        k = jnp.argmax(holding | (tops >= capacity), axis=0)[None]
        pick = lambda x: jnp.take_along_axis(x, k, axis=0)[0]  # noqa: E731
        pressure, deficit = self._smooth_min(pick(tops), capacity)
        z_flat = _bisect_pressure(terrain, pressure, self.width, pick(lowers), pick(uppers))
        return z_flat, pressure, deficit, pick(holding)

    def tread(self, entry_angle, terrain) -> Tread:
        """The flat at entry angle theta0 [rad]: half-angle theta_f = 2 arcsin sqrt(delta
        / D), its sinkage z_f, cos(theta_f) = 1 - 2 delta / D, its pressure p_f and the
        deflection delta."""
        z_flat, delta, pressure = self._flat(entry_angle, terrain)
        ratio = delta / self.diameter
        positive = ratio > 0
        half_sin = jnp.sqrt(jnp.where(positive, ratio, 1.0))
        half_angle = jnp.where(positive, 2 * jnp.arcsin(jnp.minimum(half_sin, 1.0)), 0.0)
        return Tread(half_angle, z_flat, 1 - 2 * ratio, pressure, delta)

    def contact(self, entry_angle, terrain) -> "TreadContact":
        """The contact at entry angle theta0 [rad]: the rim with the flat `tread`."""
        return TreadContact(self, entry_angle, self.tread(entry_angle, terrain))

    def flat_length(self, entry_angle: Float[ArrayLike, "..."], terrain) -> Float[Array, "..."]:
        """l = D sin(theta_f) [m]: the length of the flat at entry angle theta0 [rad]."""
        return self.diameter * jnp.sin(self.tread(entry_angle, terrain).half_angle)

    def flexing_resistance(self, tread: Tread) -> Array:
        """R_f = f_h p_f b l [N], l = 2 delta sqrt((D - delta) / (delta + delta_0)): the
        hard-surface rolling resistance at the deflection of `tread` (module docstring)."""
        delta, d = tread.deflection, self.diameter
        length = 2 * delta * jnp.sqrt((d - delta) / (delta + _DELTA_0 * d))
        return self.hard_surface_resistance * tread.pressure * self.width * length

    def deepest_reach(self, terrain) -> Array:
        """How deep the undeflected circle may sink [m]: past the base by the section
        height h (the flat stays above the base; beyond it the rim would reach the
        ground), unless the flat would rest on the base: a tyre whose p_i + p_c reaches
        the law's pressure at `BASE_CLEARANCE` z_w above the base (the snow there has
        nothing left to give) stops on the base like a rigid rim (`Status.BOTTOMED_OUT`,
        the base carrying what the snow does not)."""
        depth = terrain.depth
        return jnp.where(self._rests_on_base(terrain), depth, depth + self.section_height)

    def _rests_on_base(self, terrain) -> Array:
        """Whether p_i + p_c reaches the law's pressure `BASE_CLEARANCE` z_w above a base
        (`deepest_reach`)."""
        depth = terrain.depth
        finite = jnp.isfinite(depth)
        clearance = BASE_CLEARANCE * jnp.where(finite, depth, 1.0)
        on_base = type(terrain).pressure_at_clearance(terrain, clearance, self.width)
        return finite & (self.inflation_pressure + self.carcass_pressure >= on_base)

    def start_angles(self, terrain) -> tuple[Array]:
        """The entry angle [rad] of the switch to the elastic mode: where the rim's
        lowest-point pressure sigma(s) reaches p_i + p_c, s = D sin^2(theta0 / 2) =
        `sinkage_at_pressure(p_i + p_c)` (within the circle's reach, `deepest_reach`).
        W(theta0) bends there, from the rim's steep rise to the flat's slow one: the
        any-terrain start on a law that can fall (`start._scan_start`), which
        interpolates ln W between the entry angles it evaluates, evaluates it there too,
        so that its interpolation does not span the bend."""
        capacity = self.inflation_pressure + self.carcass_pressure
        reach = jnp.minimum(self.deepest_reach(terrain), self.diameter)
        s = type(terrain).sinkage_at_pressure(terrain, capacity, self.width, reach)
        return (2 * jnp.arcsin(jnp.sqrt(jnp.clip(s / self.diameter, 0.0, 1.0))),)

    def contact_sinkage(self, entry_angle, terrain) -> Array:
        """z_f [m]: the sinkage of the flat (the rim's, eq. 4.15, in the rigid mode)."""
        return self._flat(entry_angle, terrain)[0]


class TreadContact(AbstractContact):
    """A deflecting tyre's contact at one entry angle (module docstring): the undeflected
    circle's rim with the flat `tread` on |theta| < theta_f, at depth z_f, carrying p_f."""

    wheel: DeflectingTire
    entry_angle: Array
    tread: Tread

    def lowest_angle(self) -> Array:
        """theta_f: the flat's front end."""
        return self.tread.half_angle

    def lowest_sinkage(self) -> Array:
        """z_f, the flat's depth."""
        return self.tread.sinkage

    def _on_flat(self, theta, theta_eff):
        half = self.tread.half_angle
        return (jnp.abs(theta) < half) | (jnp.abs(theta_eff) < half)

    def rise(self, theta, theta_eff) -> Array:
        """Above the flat, `D sin^2(theta_eff / 2) - delta`; 0 on it, and wherever the
        stress angle lies on it (a rear region's points mapped onto the flat)."""
        rise = self.wheel.diameter * _sincos_half(theta_eff)[0] ** 2 - self.tread.deflection
        return jnp.where(self._on_flat(theta, theta_eff), 0.0, jnp.maximum(rise, 0.0))

    def normal_stress(self, sigma, theta, theta_eff) -> Array:
        """p_f on the flat (the law's at z_f by construction, but not in floating point
        where z_f rounds to a base), the terrain's elsewhere."""
        on_flat = self._on_flat(theta, theta_eff)
        return jnp.where(on_flat, self.tread.pressure.astype(sigma.dtype), sigma)

    def points(self, theta, sin, cos) -> ContactPoints:
        """On the flat the normal points up, (1, 0), and the length element is dx =
        r cos(theta) d theta; the tread's travel from the entry lost to the flat, per r,
        (theta_f - u) - (sin theta_f - sin u), u = clip(theta, -theta_f, theta_f),
        shortens the shear displacements.  The rim's elsewhere."""
        half = self.tread.half_angle
        u = jnp.clip(theta, -half, half)
        # sin(u) from the nodes' own sines (an XLA sine per node costs ~7 exps on CPU).
        sin_half = _sin_cos(half)[0]
        sin_u = jnp.where(theta >= half, sin_half, jnp.where(theta <= -half, -sin_half, sin))
        shortening = (half - u) - (sin_half - sin_u)
        flat = jnp.abs(theta) < half
        one, zero = jnp.ones_like(theta), jnp.zeros_like(theta)
        rim = _rim_sinkage_between(theta, self.entry_angle, self.wheel.diameter)
        depth = jnp.minimum(rim, self.tread.sinkage)
        return ContactPoints(
            shortening,
            jnp.where(flat, one, cos),
            jnp.where(flat, zero, sin),
            jnp.where(flat, cos, one),
            depth,
            type(self.wheel).contact_width(self.wheel, depth),
        )

    def moment(self, sigma, tau, theta, sin) -> Array:
        """On the flat the shear stress acts cos(theta_f) r below the axle and the normal
        stress at x = r sin theta in front of it; the rim's elsewhere."""
        flat = jnp.abs(theta) < self.tread.half_angle
        return jnp.where(flat, tau * self.tread.cos_half_angle + sigma * sin, tau)

    def panel_ends(self, distribution, slip) -> list[Array]:
        """Under a rear region, the flat's ends (the normal's direction turns there) and
        the angles whose stress angle is the flat's front end (the sinkage's kink; not
        where the rear mirrors the front, `mirrors_rear`: the integrator cuts its panels
        in the stress angle there, where that image is the front end itself).  None on
        the front region, where the flat is the contact's `smooth_span` and its front
        end the first panel's start."""
        half, theta0 = self.tread.half_angle, self.entry_angle
        if _is_front(distribution):
            return []  # the flat's front end ends its `smooth_span`
        ends = [half, -half]
        if distribution.mirrors_rear:
            return ends
        return ends + list(distribution.rear_angles(half, theta0, slip))

    def smooth_span(self, distribution) -> tuple[Array, ...]:
        """On the front region, the flat's front end theta_f (0 in the rigid mode): the
        flat carries p_f, its normal is vertical and its length element dx, so only
        the shear stress varies along it, with j linear in x.  Under a rear region,
        none (`AbstractContact.smooth_span`)."""
        return (self.tread.half_angle,) if _is_front(distribution) else ()

    def shear_sign_change(self, exit_angle, slip, rear: bool) -> tuple[Array, Array]:
        """j equals the rim's on the entry arc (theta >= theta_f); on the flat it is linear
        in sin(theta), j = j(theta_f) + i r (sin theta_f - sin theta); on the rear arc
        (theta < -theta_f) it is the rim's less r 2 (theta_f - sin theta_f).  The first
        root found, in that order (all per r: the root does not depend on the radius)."""
        theta0, half = self.entry_angle, self.tread.half_angle
        split, has_root, _ = _shear_sign_change(theta0, exit_angle, slip, 12, False)
        on_arc = has_root & (split >= half)
        j_f = _shear_displacement(half, theta0, slip, 1.0, jnp.sin(half), jnp.sin(theta0))
        lo = jnp.maximum(-half, exit_angle)
        sin_root = jnp.sin(half) + j_f / jnp.where(slip < 0, slip, -1.0)
        on_flat = (slip < 0) & (sin_root > jnp.sin(lo)) & (sin_root < jnp.sin(half))
        flat_root = jnp.arcsin(jnp.clip(sin_root, -1.0, 1.0))
        angle, found = jnp.where(on_arc, split, flat_root), on_arc | on_flat
        if not rear:
            return angle, found
        shortening = 2 * (half - jnp.sin(half))
        back, back_root, _ = _shear_sign_change(theta0, exit_angle, slip, 12, False, shortening)
        on_rear = back_root & (back < -half)
        return jnp.where(found, angle, back), found | on_rear

    def shear_slope(self, theta, slip) -> Array:
        """On the flat dj/dx = i: dj/dtheta / r = -i cos(theta); the rim's elsewhere."""
        rim = _shear_displacement_slope(jnp.cos(theta), slip)
        return jnp.where(jnp.abs(theta) < self.tread.half_angle, -slip * jnp.cos(theta), rim)

    def flexing_resistance(self) -> Array:
        """R_f of the tyre at this flat (`DeflectingTire.flexing_resistance`)."""
        return self.wheel.flexing_resistance(self.tread)
