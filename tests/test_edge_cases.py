"""The edges of the tyre, the ruts and the rover that an adversarial audit found: a stiff
tyre near a base and on a law that drops, a leader that bottoms out, a floor that rose
with a deeper rut, a rut map too large to allocate, a NaN action, and the environment's
state under Brax's and Playground's wrappers.  Each test reproduces the audit's case."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import snowjax as sj
from snowjax import Status

RIM = sj.RigidWheel.thesis_tire()
PLATE_SNOW = sj.WongSnow.thesis_plate_rule_snow()  # bottoms out above ~2.2 kN
FIELDS = ("entry_angle", "sinkage", "motion_resistance", "thrust", "drawbar_pull", "torque")


def _tire(inflation, dtype=np.float64):
    return sj.DeflectingTire(*(dtype(x) for x in (0.736, 0.235, 0.176, inflation, 0.0)))


def _cast(tree, dtype):
    return jax.tree_util.tree_map(lambda x: jnp.asarray(x, dtype), tree)


def test_a_stiff_tyre_on_the_base_of_wong_snow_is_the_rim():
    """Thesis snow with the plate rule's p_w, Wong–Reece, slip 0.2, 3 kN (more than the
    layer carries): a 1e12 Pa tyre rests on the base like the rim, with the rim's
    forces (the audit: it deflected 84 mm, R 607 N against the rim's 361 N)."""
    wr = sj.WongReece.reference()
    rim = sj.solve_wheel(RIM, sj.ContactModel(PLATE_SNOW, wr), 3000.0, 0.2)
    stiff = sj.solve_wheel(_tire(1e12), sj.ContactModel(PLATE_SNOW, wr), 3000.0, 0.2)
    assert int(rim.status) == int(stiff.status) == Status.BOTTOMED_OUT
    assert float(_tire(1e12).deflection(stiff.entry_angle, PLATE_SNOW)) < 1e-9
    for name in FIELDS:
        np.testing.assert_allclose(getattr(stiff, name), getattr(rim, name), rtol=1e-6)


def test_the_flat_carries_the_tyre_pressure_next_to_the_base_in_float32():
    """A 280 kPa tyre at 5 kN on the same snow: Wong's law reaches 280 kPa 0.08 nm above
    the base, so in float32 the flat's sinkage rounds to the base, where the law (kept
    4 ulp above it) gives 187 kPa; the flat must carry 280 kPa in both precisions (the
    audit: torque 384 N m in float32 against 324 N m, deflection 9.1 against 3.6 mm)."""
    out = {}
    for dtype in (np.float64, np.float32):
        tire, snow = _tire(280e3, dtype), _cast(PLATE_SNOW, dtype)
        st = sj.solve_wheel(tire, snow, dtype(5000.0), dtype(0.2))
        assert int(st.status) == Status.CONVERGED
        out[dtype] = (float(st.torque), float(tire.deflection(st.entry_angle, snow)))
    np.testing.assert_allclose(out[np.float32], out[np.float64], rtol=1e-3)
    np.testing.assert_allclose(out[np.float64][1], 3.56e-3, rtol=1e-2)


def test_a_stiff_tyre_on_layered_snow_breaks_the_ice_where_the_rim_does():
    """`LayeredSnow.ice_layer_example()`, 2 kN, slip 0.2: the rim breaks the ice (60 kPa)
    and sinks to 156 mm; a tyre that can press more than the ice holds (61 kPa and
    up, to 1e12 Pa) follows it, one that cannot (45 kPa) rides on the ice (the audit:
    every tyre from 45 kPa to 1e12 Pa 'deflected' 95 mm, sank 63 mm, R 186 N)."""
    snow = sj.LayeredSnow.ice_layer_example()
    inflations = np.array([45e3, 61e3, 1e12])
    tires = _tire(inflations)
    rim = sj.solve_wheel(RIM, snow, 2000.0, 0.2)
    st = sj.solve_wheel(tires, snow, 2000.0, 0.2)
    assert np.all(np.asarray(st.status) == Status.CONVERGED)
    np.testing.assert_allclose(float(rim.sinkage), 0.1565, rtol=1e-3)
    for name in FIELDS:
        np.testing.assert_allclose(getattr(st, name)[1:], getattr(rim, name), rtol=1e-6)
    assert float(st.sinkage[0]) < float(snow.failure_sinkage)  # on the ice
    deflection = np.asarray(tires.deflection(st.entry_angle, snow))
    assert deflection[0] > 0.01 and deflection[2] < 1e-12


def test_a_leader_that_bottoms_out_leaves_a_rut_a_follower_rests_in():
    """Thesis snow, two 20 kN wheels in one track: the first rests on the base, the
    second on the rut it leaves there (the audit: `ValueError` eagerly, NaN under jit)."""
    snow = sj.WongSnow.thesis_fresh_snow()
    loads = jnp.array([20e3, 20e3])
    for run in (sj.multi_pass, jax.jit(sj.multi_pass)):
        res = run(RIM, snow, loads, 0.2, 1e6, 5e6)
        assert np.all(np.asarray(res.status) == Status.BOTTOMED_OUT)
        np.testing.assert_allclose(res.rut_depth, float(snow.z_w), rtol=1e-12)
        for leaf in jax.tree_util.tree_leaves(res):
            assert np.all(np.isfinite(np.asarray(leaf)))


def test_vehicles_and_the_rut_map_run_where_the_leaders_bottom_out():
    """The ruts guide's 4 x 3.5 kN vehicle on the plate-rule snow (which carries ~2.2 kN):
    the longitudinal and planar force functions with `Ruts` are finite with finite
    slopes (the audit: speed inf from the first step), and `drive_path` marks finite
    depths, none below the base (the audit: NaN cells)."""
    from snowjax._sim.planar import _planar_wheel_forces
    from snowjax._sim.vehicle import _wheel_forces

    contact = sj.ContactModel(PLATE_SNOW)
    ruts = sj.Ruts(1e6, 5e6, (-1, -1, 0, 1))
    radius = float(RIM.diameter) / 2

    def longitudinal(omega):
        f = _wheel_forces(jnp.array([[1.0]]), omega, 3500.0, RIM, contact, 0.05, None, 64, ruts)
        return f.longitudinal_force, f

    omega = jnp.full((1, 4), 1.0 / radius / 0.8)
    slopes, f = jax.jit(jax.jacfwd(longitudinal, has_aux=True))(omega)
    assert np.all(np.isfinite(np.asarray(slopes))) and np.all(np.isfinite(f.longitudinal_force))
    assert np.all(np.asarray(f.status) == Status.BOTTOMED_OUT)
    np.testing.assert_array_equal(f.longitudinal_force[0, 2:], 0.0)  # rear: on the base
    mass = 4 * 3500.0 / 9.80665
    vehicle = sj.PlanarVehicle(mass, mass * (2.5**2 + 1.5**2) / 12, 1.5, RIM, 2.5, 1.5)
    contact = sj.ContactModel(PLATE_SNOW, None, "classic", sj.Lateral())

    def planar(omega):
        out = _planar_wheel_forces(
            vehicle,
            contact,
            *jnp.array([1.5, 0.05, 0.04]),
            omega,
            jnp.zeros(4),
            0.05,
            None,
            64,
            ruts,
        )
        return out.drawbar_pull, out

    slopes, out = jax.jit(jax.jacfwd(planar, has_aux=True))(jnp.full(4, 1.5 / radius / 0.8))
    for leaf in (slopes, *jax.tree_util.tree_leaves(out)):
        assert np.all(np.isfinite(np.asarray(leaf)))
    rut_map = sj.RutMap.empty((-1.0, 5.0, -1.0, 1.0), 0.05, 1e6, 5e6)
    s = jnp.arange(12) * 0.125
    positions = jnp.stack([jnp.stack([s + 2.5, 0 * s], -1), jnp.stack([s, 0 * s], -1)], 1)
    path = sj.drive_path(RIM, PLATE_SNOW, rut_map, positions, jnp.zeros((12, 2)), 3500.0, 0.2)
    cells = np.asarray(path.rut_map.depth)
    assert np.all(np.isfinite(cells)) and cells.max() <= float(PLATE_SNOW.z_w)
    np.testing.assert_allclose(cells.max(), float(PLATE_SNOW.z_w), rtol=1e-12)
    for leaf in jax.tree_util.tree_leaves(path):
        assert np.all(np.isfinite(np.asarray(leaf)))


def test_a_deeper_rut_never_leaves_a_shallower_floor():
    """The audit's case (thesis snow, k_0 1 MPa/m, A_u 5 MPa/m^2): the floor after a
    161 mm wheel lay 83.5 mm down, after one that reached z_w - 0.2 um at the original
    surface, where a 3.5 kN follower sank 27 mm (116.8 mm on virgin snow).  Now the
    floor deepens with the rut up to the base (on a fine grid here; every built-in law
    in `tests/test_properties.py`), and the follower on the rut pressed nearly to the
    base rests on the base."""
    snow = sj.WongSnow.thesis_fresh_snow()
    z_w = float(snow.z_w)
    z_u = jnp.asarray(np.concatenate([np.linspace(0.0, z_w, 4001), [0.161, z_w - 2e-7]]))
    floor = np.asarray(sj.Rut(snow, z_u, RIM.width, 1e6, 5e6).floor_depth)
    assert np.all(np.diff(floor[:4001]) >= 0)
    assert floor[-2] < floor[-1] <= z_w and floor[-1] > z_w - 1e-5
    st = sj.solve_wheel(RIM, sj.Rut(snow, z_w - 2e-7, RIM.width, 1e6, 5e6), 3500.0, 0.2)
    assert int(st.status) == Status.BOTTOMED_OUT  # on the base, under the floor
    assert float(st.sinkage) <= float(z_w - floor[-1]) * (1 + 1e-9)


def test_a_rut_map_too_large_to_allocate_is_refused_before_allocating():
    """A 10 m x 5 m map of 1 nm cells aborted the interpreter (an XLA C++ terminate);
    1 um cells asked XLA for 200 TB."""
    for cell, memory in ((1e-9, "PiB"), (1e-6, "TiB")):
        with pytest.raises(ValueError, match=rf"cell_size = {cell:.3g} m .* {memory}"):
            sj.RutMap.empty((0.0, 10.0, 0.0, 5.0), cell, 1e6, 5e6)
    with pytest.raises(ValueError, match="window"):
        sj.RutMap.empty((0.0, 1.0, 0.0, 1.0), 1e-3, 1e6, 5e6, reach=100.0)
    small = sj.RutMap.empty((0.0, 10.0, 0.0, 5.0), 1e-3, 1e6, 5e6, max_bytes=2**29)
    assert small.nbytes == 10_000 * 5_000 * small.depth.dtype.itemsize
    assert math.isclose(small.cell_size, 1e-3)
