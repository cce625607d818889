"""Shear laws of the rim: how the shear stress mobilises along the contact.

Every function with a `shear` argument takes one of these modules or its name:
`JanosiHanamoto()` (`"classic"`, eq. 4.11), `ThesisSimplified()` (`"simplified"`,
eq. 4.13) or `NoShear()` (`"none"`), or a law written outside the package.  A law is
one method, `mobilisation`: the factor g in tau = (c + sigma tan phi) g.  Everything
else the quadrature needs has a default built from it or from the rim's geometry: the
combined law under a slip angle (the resultant of the displacements, `Lateral`), the
width of the layer behind the entry over which g rises (`entry_layer`), where a braked
wheel's shear stress changes sign (`braking_panels`: where the shear displacement 4.10
does), g and dg/dtheta at the axle (taken by the closed-form rule from `mobilisation`
itself), the default numbers of nodes, and the name a sweep records (the class name).
A law overrides a default only where its physics differs: the thesis's simplified law
(derived from Wong's pressure–sinkage law on the front region) says what it needs of the
terrain (`check`, `constraints`), where its stress changes sign, and that it has no
lateral counterpart.
"""

import abc
from typing import ClassVar, Literal

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array

from .._terrain.shear import _signed_mobilisation
from .._terrain.wong import WongSnow
from .distribution import _as_distribution, _is_front
from .geometry import _layer_width, _shear_displacement_slope, _shear_sign_change, _sincos_half
from .lateral import combined_mobilisation

__all__ = ["AbstractShearLaw", "JanosiHanamoto", "ThesisSimplified", "NoShear"]

ShearModel = Literal["classic", "simplified", "none"]


STRICT_COHESION = "> 0 Pa (the simplified model is normalised by c)"


def _axle_gap(dtype) -> float:
    """Sign changes of the shear stress closer to the axle than this fraction of theta0 are
    left to the first panel (which then misses a layer at most that wide).  1e-9 in
    float64; 1e-3 in float32, where a split closer to the axle would put nodes so close
    to theta = 0 that sin^2(theta / 2) underflows (infinite pressure on a bottomed-out
    wheel)."""
    return 1e-9 if jnp.dtype(dtype) == jnp.float64 else 1e-3


class AbstractShearLaw(eqx.Module):
    """A shear law of the rim (abstract): tau = (c + sigma tan phi) g, the law giving the
    mobilisation factor g [-].

    A law implements one method, `mobilisation`; every other method and class variable
    has a default (see the module's docstring) that a law overrides only where its physics
    differs.  Angles in rad from the vertical through the wheel centre (theta0 the entry
    angle), slip the driving slip i [-] (2.6), lengths in m, stresses in Pa.
    """

    #: The law's name: what `sweep` records (default: the class name).
    name: ClassVar[str]
    #: Whether the law has a shear stress at all (`NoShear`: no).
    mobilises: ClassVar[bool] = True
    #: Whether it has a lateral counterpart for a slip angle (`combined_mobilisation`).
    lateral: ClassVar[bool] = True
    #: Whether the vehicle simulations accept it (a law that can deliver power to a
    #: braked wheel is refused there).
    in_simulations: ClassVar[bool] = True
    #: Default nodes of the closed-form rule (Wong snow on the front region): nodes of
    #: its two-panel rule (no element brakes) and of each panel of its four-panel rule,
    #: chosen so that every contact integral stays within 1e-7 of adaptive quadrature
    #: over the documented range (tests; measured worst cases: classic 4e-8 driving and
    #: 9e-8 braking, simplified 3e-9 driving, none 4e-10).  The default is the classic
    #: law's, whose entry panel needs only 8 nodes.
    nodes_closed_form: ClassVar[tuple[int, tuple[int, int, int, int]]] = (10, (10, 10, 10, 8))
    #: Default nodes per half-panel of the any-terrain rule (without, with braking); None:
    #: the law has no any-terrain rule.  A contact that is one panel with a smooth lower
    #: end takes ceil(5 n / 3) nodes on it instead (`general._graded_panel`), and a
    #: driven one cut inside under Wong–Reece n on each piece, ceil(5 n / 3) on the
    #: piece at the entry (`general._cut_panels`).
    nodes_any_terrain: ClassVar[tuple[int, int] | None] = (12, 16)
    #: Nodes at the simulator accuracy (`ContactModel(accuracy="simulator")`): on every
    #: panel of the closed-form rule, and on every half-panel of the any-terrain rule
    #: (None: no any-terrain rule).  Their error against adaptive quadrature over the
    #: random cases of every law is measured by `benchmarks/accuracy.py` (the
    #: performance guide's table).
    nodes_simulator: ClassVar[tuple[int, int | None]] = (6, 8)

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if "name" not in cls.__dict__:
            cls.name = cls.__name__

    @abc.abstractmethod
    def mobilisation(self, j, modulus, sigma, theta0, slip, diameter, terrain) -> Array:
        """The factor g [-] at rim points with shear displacement j [m] (4.10), shear
        modulus K [m] and normal stress sigma [Pa], of a wheel of diameter D [m] at
        entry angle theta0 and slip i on `terrain`.  An odd function of j for a law of
        the displacement (a braked wheel's stress points backwards where j < 0)."""

    def check(self, terrain, distribution) -> None:
        """Raise `ValueError` if the law does not apply to this terrain and distribution
        (`FrontRegion()`, or its short spelling None, for the front region); default: it
        applies everywhere."""

    def constraints(self, terrain) -> list[tuple[str, Array, Array, str]]:
        """Rules the law adds to the terrain's parameters: (field, value, ok mask,
        allowed range), e.g. a strictly positive cohesion for a law normalised by c;
        default: none."""
        return []

    def combined_mobilisation(self, x, y, sigma, theta0, slip, diameter, terrain):
        """(g_x, g_y) [-] under a slip angle, for modulus-scaled displacements x = j / K
        and y = j_y / K_y (`Lateral`): the law taken along the resultant displacement
        u = hypot(x, y), `(x, y) g(u) / u` (g(u) / u -> g'(0) at u = 0)."""

        def along(u):
            one = jnp.ones_like(u)
            return self.mobilisation(u, one, sigma, theta0, slip, diameter, terrain)

        q = x * x + y * y
        positive = q > 0
        u = jnp.sqrt(jnp.where(positive, q, 1.0))
        zero = jnp.zeros_like(u)
        slope = jax.jvp(along, (zero,), (jnp.ones_like(u),))[1]
        factor = jnp.where(positive, along(u) / u, slope)
        return x * factor, y * factor

    def entry_layer(self, theta0, slip, diameter, terrain, modulus) -> Array:
        """Width [rad] of the layer behind the entry angle over which g rises (the linear
        rise of j / K, K = `modulus` [m]); `inf` without shear stress."""
        slope = _shear_displacement_slope(jnp.cos(theta0), slip)
        return _layer_width(modulus, diameter / 2, slope)

    def braking_panels(self, theta0, slip, diameter, terrain, z0_rel, entry_scale, lateral_rate):
        """Panels of the closed-form rule's four-panel layout: (b1, split, b3, scale2,
        scale3, scale4), the panels [0, b1], [b1, split], [split, b3], [b3, theta0] and
        the sinh scales [rad] of the last three (`z0_rel` = 1 - z0 / depth, the relative
        distance of the lowest rim point to the base; `entry_scale` [rad], the running's
        width of the entry layer; `lateral_rate` [1/rad], the running's growth of
        j_y / K_y behind the entry, 0 running straight).

        Default: the sign change of the shear displacement, the sign change of g for a
        law of j.  j(theta) / r = (theta0 - theta) - k (sin theta0 - sin theta),
        k = 1 - i, vanishes at the entry; for a braked wheel with k cos theta0 > 1 it
        rises from the entry to a maximum at theta* = arccos(1 / k) and, if j(0) < 0,
        falls through zero at the split below theta* (backward shear near the axle, a
        kink in the stress).  Panels: [0, split / 2] (quadratic map at the axle),
        [split / 2, split] and [split, b3] clustered at the split with the linear layer
        width K / (r |dj/dtheta|), and [b3, theta0] clustered at the entry with twice the
        entry layer width.  b3 is theta*, kept within the middle 60 % of [split,
        theta0]: each of the last two panels then holds one monotone branch of j.
        Without a sign change the split is theta0 / 2 and b3 the midpoint of [split,
        theta0].

        At a slip angle the lateral displacement u_y = j_y / K_y (`lateral_rate` times
        theta0 - split at the split) rounds the kink: |u| = hypot(u_x, u_y) turns over
        |theta - split| ~ u_y K / (r |dj/dtheta|), so the two panels beside the split
        cluster at that width, kept between 1 % of theta0 - split and the straight
        layer's width (the rule at a slip angle gives these two panels 16 nodes,
        `SteeredRimRule`)."""
        th, has_root, theta_star = _shear_sign_change(theta0, None, slip, 8, True)
        slope = _shear_displacement_slope(1 - 2 * _sincos_half(th)[0] ** 2, slip)
        split_scale = _layer_width(terrain.shear_modulus, diameter / 2, slope)
        rounded = lateral_rate * (theta0 - th) * split_scale
        split_scale = jnp.where(
            rounded > 0, jnp.clip(rounded, 0.01 * (theta0 - th), split_scale), split_scale
        )
        has_root = has_root & (th > _axle_gap(theta0.dtype) * theta0)
        split = jnp.where(has_root, th, theta0 / 2)
        gap = theta0 - split
        b3 = jnp.where(
            has_root,
            jnp.clip(theta_star, split + 0.2 * gap, theta0 - 0.2 * gap),
            split + 0.5 * gap,
        )
        scale = jnp.where(has_root, split_scale, jnp.inf)
        return split / 2, split, b3, scale, scale, 2 * entry_scale


class JanosiHanamoto(AbstractShearLaw):
    """Janosi–Hanamoto on the rigid-wheel shear displacement, eq. (4.11) (`"classic"`):
    `tau = (c + sigma tan phi)[1 - exp(-j / K)]`, j from (4.10), mirrored for j < 0.
    Every terrain and distribution; with a slip angle, the combined law of `Lateral`."""

    name: ClassVar[str] = "classic"

    def mobilisation(self, j, modulus, sigma, theta0, slip, diameter, terrain):
        """`sign(j) (1 - exp(-|j| / K))` (4.11, mirrored for j < 0)."""
        return _signed_mobilisation(j / modulus)

    def combined_mobilisation(self, x, y, sigma, theta0, slip, diameter, terrain):
        """The resultant law of `Lateral` (`combined_mobilisation`): the default's, in
        closed form."""
        return combined_mobilisation(x, y)


# Level of |U0| beyond which the mobilisation is saturated to rounding: exp(-40) = 4e-18.
_SATURATED_U0 = 40.0


def _simplified_coefficients(entry_angle, diameter, snow):
    """tau_1 and tau_2 of eq. (4.13), evaluated at the current entry angle."""
    u_k = diameter / snow.shear_modulus
    tau1 = u_k * (snow.z_w / diameter) * (snow.cohesion / snow.p_w) / jnp.tan(entry_angle)
    tau2 = 1 / jnp.cos(entry_angle) - 1
    return tau1, tau2


def _simplified_exponent(sigma_bar, slip, tau1, tau2):
    """U0 of eq. (4.13): `(i + tau2) tau1 s + (2i - i^2) tau1 s^3 / 6`, s = sigma / c."""
    return (slip + tau2) * tau1 * sigma_bar + (2 * slip - slip**2) * tau1 * sigma_bar**3 / 6


def _theta_at_sigma_bar(s, snow, z0_rel, a):
    """Rim angle where sigma / c = s (Wong's law on the rim, inverted); 0 past the axle."""
    z = jnp.exp(-snow.cohesion / snow.p_w * s)
    return 2 * jnp.arcsin(jnp.sqrt(jnp.clip((z - z0_rel) / (2 * a), 0.0, 1.0)))


class ThesisSimplified(AbstractShearLaw):
    """The thesis's simplified shear law, eq. (4.13) (`"simplified"`): derived from Wong's
    pressure–sinkage law on the front region, so it needs a `WongSnow` and the
    front-region distribution; no slip angle, and not in the vehicle simulations (its
    braking extension can deliver power to the wheel).

    `tau = c (1 + sigma_bar tan phi)[1 - exp(-U0)]`, `sigma_bar = sigma / c`,
    `U0 = (i + tau2) tau1 sigma_bar + (2i - i^2) tau1 sigma_bar^3 / 6`,
    `tau1 = (D / K)(z_w / D)(c / p_w) cot theta0`, `tau2 = 1 / cos theta0 - 1`, with tau1
    and tau2 evaluated at the current entry angle; mirrored for U0 < 0.
    """

    name: ClassVar[str] = "simplified"
    lateral: ClassVar[bool] = False
    in_simulations: ClassVar[bool] = False
    nodes_any_terrain: ClassVar = None
    # The cubic exponent makes its shear layer steeper than the classic law's: more
    # nodes (measured worst case 3e-9 driving against adaptive quadrature).
    nodes_closed_form: ClassVar = (24, (16, 16, 16, 16))
    nodes_simulator: ClassVar = (8, None)

    def check(self, terrain, distribution) -> None:
        """`ValueError` unless the terrain is `WongSnow` on the front region."""
        if not (_is_front(_as_distribution(distribution)) and isinstance(terrain, WongSnow)):
            raise ValueError(
                "shear='simplified' (eq. 4.13) is derived from Wong's law on the front region "
                "of the contact: it needs a WongSnow terrain and distribution=None; use "
                "shear='classic' for other terrains and for the Wong–Reece distribution."
            )

    def constraints(self, terrain):
        """The law is normalised by c: a strictly positive cohesion."""
        return [("cohesion", terrain.cohesion, terrain.cohesion > 0, STRICT_COHESION)]

    def mobilisation(self, j, modulus, sigma, theta0, slip, diameter, terrain):
        """`sign(U0) (1 - exp(-|U0|))` (4.13); j and K unused."""
        tau1, tau2 = _simplified_coefficients(theta0, diameter, terrain)
        return _signed_mobilisation(
            _simplified_exponent(sigma / terrain.cohesion, slip, tau1, tau2)
        )

    def entry_layer(self, theta0, slip, diameter, terrain, modulus):
        """The smaller of the linear rise's width and that of U0's cubic term:
        sigma_bar ~ k1 (theta0 - theta) near the entry, so |2i - i^2| tau1 (k1 d)^3 / 6 = 1
        at d = 1 / (k1 cbrt(|2i - i^2| tau1 / 6))."""
        scale = AbstractShearLaw.entry_layer(self, theta0, slip, diameter, terrain, modulus)
        tau1, _ = _simplified_coefficients(theta0, diameter, terrain)
        a = diameter / (2 * terrain.z_w)
        k1 = terrain.p_w / terrain.cohesion * a * jnp.sin(theta0)
        cubic = jnp.abs(2 * slip - slip**2) * tau1 / 6
        return jnp.minimum(scale, 1 / (k1 * jnp.cbrt(cubic) + 1e-300))

    def braking_panels(self, theta0, slip, diameter, terrain, z0_rel, entry_scale, lateral_rate):
        """U0 = tau1 s (A - B s^2), s = sigma / c, A = i + tau2, B = (i^2 - 2i) / 6, is a
        cubic in s, and s falls monotonically from the axle to the entry, so every level
        of |U0| is reached at an angle known from a root of the cubic
        (`_theta_at_sigma_bar`).  The mobilisation varies only where |U0| < 40; the
        nodes must resolve that layer, all the more because the integrands of the
        derivatives (~ U0 exp(-|U0|)) live only there.

        - U0 changes sign at s_r = sqrt(A / B) (i < 0 < A).  Below the split (s > s_r)
          |U0| grows like the cubic, much faster than its slope at the root suggests:
          panel 2 is [theta(|U0| = 40), split] (at least [split / 2, split]) and clusters
          at the split with twice the distance to |U0| = 1; panel 3 clusters at the
          split with four times the linear scale 1 / |dU0/dtheta|, panel 4 at the entry
          as without a split.
        - No sign change: |U0| = tau1 s (|A| + |B| s^2) grows monotonically from the
          entry; panel 4 is [theta(|U0| = 40), theta0] (at least the upper half of
          [theta0 / 2, theta0]) and clusters at theta0 with the distance to |U0| = 1 (or
          the entry scale, if less).
        """
        snow = terrain
        a = diameter / (2 * snow.z_w)
        tiny = jnp.finfo(theta0.dtype).tiny
        tau1, tau2 = _simplified_coefficients(theta0, diameter, snow)
        big_a = slip + tau2
        big_b = (slip**2 - 2 * slip) / 6
        sign_change = (slip < 0) & (big_a > 0)
        s_root = jnp.sqrt(jnp.where(sign_change, big_a / jnp.where(sign_change, big_b, 1.0), 0.0))
        th_root = _theta_at_sigma_bar(s_root, snow, z0_rel, a)
        z_root = jnp.exp(-snow.cohesion / snow.p_w * s_root)
        gap = _axle_gap(theta0.dtype) * theta0
        has_root = sign_change & (z_root > z0_rel) & (th_root < theta0) & (th_root > gap)
        # |U0| = tau1 s (bb s^2 - aa) beyond the root (s > s_r), or from the entry when U0
        # has one sign; increasing and convex there, so Newton from an upper bound
        # converges monotonically: s_r + cbrt(level / (tau1 B)) beyond a root, else the
        # smaller of cbrt(level / (tau1 |B|)) and level / (tau1 |A|) (within a factor 2
        # of the root).  A sign change left to the first panel counts as none: the
        # levels are then those of the upper bound tau1 s (|A| + |B| s^2) of |U0|,
        # reached from the entry.
        aa = jnp.where(has_root, big_a, -jnp.abs(big_a))
        bb = jnp.maximum(jnp.abs(big_b), tiny)
        s_floor = jnp.where(has_root, s_root, 0.0)

        def s_at(level):
            # cbrt of each factor: B ~ -i / 3 can be ~1e-37 (float32 slip of -1e-36), and
            # level / (tau1 B) would overflow.
            c3 = jnp.cbrt(level / tau1) / jnp.cbrt(bb)
            s = jnp.where(
                has_root, s_root + c3, jnp.minimum(c3, level / jnp.maximum(-tau1 * aa, tiny))
            )
            for _ in range(8):
                f = tau1 * s * (bb * s**2 - aa) - level
                slope = jnp.maximum(tau1 * (3 * bb * s**2 - aa), tiny)
                s = jnp.maximum(s - f / slope, s_floor)
            return s

        th_1 = _theta_at_sigma_bar(s_at(1.0), snow, z0_rel, a)
        th_sat = _theta_at_sigma_bar(s_at(_SATURATED_U0), snow, z0_rel, a)
        # |dU0/dtheta| at the root: dU0/ds * ds/dtheta.
        du_ds = tau1 * (big_a - 3 * big_b * s_root**2)
        ds_dth = snow.p_w / snow.cohesion * a * jnp.sin(th_root) / jnp.maximum(z_root, tiny)
        linear = 1 / jnp.maximum(jnp.abs(du_ds * ds_dth), 1e-12)
        split = jnp.where(has_root, th_root, theta0 / 2)
        b1 = jnp.where(has_root, jnp.maximum(split / 2, th_sat), split / 2)
        b3 = jnp.where(has_root, (split + theta0) / 2, jnp.maximum((split + theta0) / 2, th_sat))
        scale2 = jnp.where(has_root, 2 * jnp.minimum(th_root - th_1, linear), jnp.inf)
        scale3 = jnp.where(has_root, 4 * linear, jnp.inf)
        scale4 = jnp.where(has_root, entry_scale, jnp.minimum(theta0 - th_1, entry_scale))
        return b1, split, b3, scale2, scale3, scale4


class NoShear(AbstractShearLaw):
    """No shear stress (`"none"`): the normal stress alone (motion resistance and sinkage)."""

    name: ClassVar[str] = "none"
    mobilises: ClassVar[bool] = False
    nodes_closed_form: ClassVar = (8, (8, 8, 8, 8))
    nodes_any_terrain: ClassVar = (12, 12)

    def mobilisation(self, j, modulus, sigma, theta0, slip, diameter, terrain):
        """0."""
        return jnp.zeros_like(sigma)

    def combined_mobilisation(self, x, y, sigma, theta0, slip, diameter, terrain):
        """(0, 0)."""
        return jnp.zeros_like(x), jnp.zeros_like(x)

    def entry_layer(self, theta0, slip, diameter, terrain, modulus):
        """`inf`: no layer."""
        return jnp.full_like(theta0, jnp.inf)

    def braking_panels(self, theta0, slip, diameter, terrain, z0_rel, entry_scale, lateral_rate):
        """Four equal panels (no shear stress, no layer to resolve)."""
        inf = jnp.full_like(theta0, jnp.inf)
        return theta0 / 4, theta0 / 2, 0.75 * theta0, inf, inf, inf


SHEAR_LAWS: dict[str, AbstractShearLaw] = {
    law.name: law for law in (JanosiHanamoto(), ThesisSimplified(), NoShear())
}


def _shear_law(shear) -> AbstractShearLaw:
    """The shear-law module for a module or its name; `ValueError` for anything else."""
    if isinstance(shear, AbstractShearLaw):
        return shear
    if isinstance(shear, str) and shear in SHEAR_LAWS:
        return SHEAR_LAWS[shear]
    raise ValueError(
        f"shear must be one of {tuple(SHEAR_LAWS)} or a snowjax shear law "
        f"(JanosiHanamoto(), ThesisSimplified(), NoShear()), got {shear!r}"
    )
