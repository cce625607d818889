"""Every wrong argument to solve_wheel is a clear, eager error naming the argument.

Ordinary inputs that are not arrays (lists, Python scalars) are accepted; an empty batch
gives empty results.
"""

import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import snowjax as sj

WHEEL = sj.RigidWheel.thesis_tire()
SNOW = sj.WongSnow.thesis_fresh_snow()


def test_a_list_is_an_array():
    listed = sj.solve_wheel(WHEEL, SNOW, [3500.0, 5000.0], 0.3)
    arrayed = sj.solve_wheel(WHEEL, SNOW, np.array([3500.0, 5000.0]), 0.3)
    np.testing.assert_array_equal(listed.sinkage, arrayed.sinkage)
    assert np.all(np.asarray(listed.status) == 0)


def test_an_empty_batch_gives_empty_results():
    st = sj.solve_wheel(WHEEL, SNOW, np.zeros((0, 3)), 0.3)
    assert st.sinkage.shape == (0, 3) and st.status.shape == (0, 3)
    assert st.status.dtype == np.int32


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"load": np.full(3, 4e3), "slip": np.full(4, 0.3)}, ValueError,
         "input shapes do not broadcast together (NumPy rules): load (3,), slip (4,)"),
        ({"load": "5000"}, TypeError, "load must be a real number or array, got a string"),
        ({"slip": "0.3"}, TypeError, "slip must be a real number or array, got a string"),
        ({"load": 5000 + 1j}, TypeError, "load must be a real number or array, got a complex"),
        ({"load": True}, TypeError, "load must be a real number or array, got a boolean"),
        ({"slip": np.array([True])}, TypeError, "slip must be a real number or array, got a bool"),
        ({"load": None}, TypeError, "load must be a real number or array, got None"),
        ({"load": [[1e3, 2e3], [3e3]]}, TypeError, "load must be a real number or array"),
        ({"nodes_per_panel": 12}, TypeError,
         "solve_wheel(nodes_per_panel=...) is now spelled ContactModel(terrain, nodes_per_panel"),
        ({"max_steps": -1}, ValueError, "max_steps must be an integer >= 1, got -1"),
        ({"max_steps": 3.5}, ValueError, "max_steps must be an integer >= 1, got 3.5"),
        ({"initial_entry_angle": "x"}, TypeError, "initial_entry_angle must be a real number"),
    ],
)  # fmt: skip
def test_bad_arguments_are_named(kwargs, error, message):
    args = {"load": 5000.0, "slip": 0.3} | kwargs
    load, slip = args.pop("load"), args.pop("slip")
    with pytest.raises(error, match=re.escape(message)):
        sj.solve_wheel(WHEEL, SNOW, load, slip, **args)


@pytest.mark.parametrize(
    ("value", "error", "message"),
    [(2.5, TypeError, "nodes_per_panel must be None or an int, got 2.5"),
     (True, TypeError, "nodes_per_panel must be None or an int, got True"),
     (1, ValueError, "nodes_per_panel must be >= 2, got 1")],
)  # fmt: skip
def test_the_models_nodes_per_panel_is_checked(value, error, message):
    with pytest.raises(error, match=re.escape(message)):
        sj.ContactModel(SNOW, nodes_per_panel=value)


def test_a_parameter_shape_clash_names_the_leaf():
    snow = sj.WongSnow(np.full(2, 85e3), 0.2, 18e3, 0.08, 0.01)
    with pytest.raises(ValueError, match=re.escape("snow.p_w (2,)")):
        sj.solve_wheel(WHEEL, snow, np.full(3, 4e3), 0.3)


def test_traced_inputs_still_work():
    f = jax.jit(lambda load: sj.solve_wheel(WHEEL, SNOW, load, 0.3).sinkage)
    np.testing.assert_allclose(
        f(np.array([4e3, 5e3])), sj.solve_wheel(WHEEL, SNOW, [4e3, 5e3], 0.3).sinkage, rtol=1e-12
    )


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: sj.WongSnow(True, 0.2, 18e3, 0.08, 0.01), "WongSnow.p_w must be a real number"),
        (lambda: sj.RigidWheel(0.7, "0.2"), "RigidWheel.width must be a real number"),
        (lambda: sj.BekkerSoil(1.0, 1 + 2j, 1e5, 1e3, 0.3), "BekkerSoil.k_c must be a real"),
        (lambda: sj.WongReece(np.array([True]), 0.3), "WongReece.c1 must be a real number"),
    ],
)
def test_parameter_leaves_must_be_real(make, message):
    with pytest.raises(TypeError, match=re.escape(message)):
        make()


@pytest.mark.parametrize(
    ("field", "value"),
    [("p_w", 1e300), ("cohesion", 1e-300), ("z_w", 1e-300), ("shear_modulus", 1e90)],
)
def test_values_the_working_precision_cannot_carry_are_invalid(field, value):
    params = dict(p_w=85e3, z_w=0.2, cohesion=18e3, tan_phi=0.08, shear_modulus=0.01)
    snow = sj.WongSnow(**(params | {field: value}))
    with pytest.raises(ValueError, match=re.escape(f"snow.{field} = {value!r} is outside")):
        sj.solve_wheel(WHEEL, snow, 5000.0, 0.3)
    # Traced: the element is INVALID_INPUT (NaN fields), its neighbour is solved.
    batch = sj.WongSnow(**(params | {field: np.array([value, params[field]])}))
    st = jax.jit(lambda s: sj.solve_wheel(WHEEL, s, 5000.0, 0.3))(batch)
    assert list(np.asarray(st.status)) == [sj.Status.INVALID_INPUT, sj.Status.CONVERGED]
    assert np.isnan(st.sinkage[0]) and np.isfinite(st.sinkage[1])


def test_reused_parameter_sets_are_still_checked_with_each_load_and_slip():
    """A wheel and terrain already validated are not re-checked, but loads and slips are,
    and a different (invalid) terrain object is checked afresh."""
    snow = sj.WongSnow(85e3, 0.2, 18e3, 0.08, 0.01)
    sj.solve_wheel(WHEEL, snow, 4e3, 0.3)
    with pytest.raises(ValueError, match="load must be finite and > 0 N"):
        sj.solve_wheel(WHEEL, snow, -4e3, 0.3)
    with pytest.raises(ValueError, match=re.escape("slip must be finite and in [-1, 1]")):
        sj.solve_wheel(WHEEL, snow, 4e3, 1.5)
    del snow
    bad = sj.WongSnow(-85e3, 0.2, 18e3, 0.08, 0.01)
    with pytest.raises(ValueError, match="snow.p_w must be finite and > 0 Pa"):
        sj.solve_wheel(WHEEL, bad, 4e3, 0.3)
    # The simplified model needs c > 0: the same terrain is checked again for it.
    no_cohesion = sj.WongSnow(85e3, 0.2, 0.0, 0.08, 0.01)
    sj.solve_wheel(WHEEL, no_cohesion, 4e3, 0.3)
    with pytest.raises(ValueError, match="snow.cohesion must be finite and > 0 Pa"):
        sj.solve_wheel(WHEEL, sj.ContactModel(no_cohesion, shear="simplified"), 4e3, 0.3)


def test_a_checked_wheel_and_terrain_still_check_the_distribution():
    """The eager checks remember a validated (wheel, terrain) pair; the distribution's
    slip-dependent rules are checked on every call all the same."""
    wheel = sj.RigidWheel(jnp.asarray(0.8), jnp.asarray(0.3))
    soil = sj.BekkerSoil.snow_us()
    sj.solve_wheel(wheel, sj.ContactModel(soil, sj.WongReece(0.43, 0.32)), 800.0, 0.2)
    with pytest.raises(ValueError, match=r"distribution\.c1 \+ c2 \* slip"):
        sj.solve_wheel(wheel, sj.ContactModel(soil, sj.WongReece(-0.5, 0.32)), 800.0, 0.2)


def test_a_checked_lateral_law_and_term_still_check_what_changes():
    """The lateral law and force terms of a model are checked once per object (their
    leaves are JAX arrays, immutable); the slip angle on every call, and a new object
    afresh."""
    lateral = sj.Lateral(shear_modulus=0.02)
    model = sj.ContactModel(SNOW, lateral=lateral, terms=(Drag(jnp.asarray(1e3)),))
    sj.solve_wheel(WHEEL, model, 4e3, 0.3, slip_angle=0.1)
    with pytest.raises(ValueError, match=re.escape("slip_angle must be finite and in (-pi/2")):
        sj.solve_wheel(WHEEL, model, 4e3, 0.3, slip_angle=2.0)
    bad = sj.ContactModel(SNOW, lateral=sj.Lateral(shear_modulus=-0.02))
    for _ in range(2):  # a failed check is not remembered
        with pytest.raises(ValueError, match=r"lateral\.shear_modulus must be finite and > 0"):
            sj.solve_wheel(WHEEL, bad, 4e3, 0.3, slip_angle=0.1)
    bad = sj.ContactModel(SNOW, lateral=lateral, terms=(Drag(jnp.asarray(np.nan)),))
    for _ in range(2):
        with pytest.raises(ValueError, match=r"terms\[0\]\.pressure must be finite"):
            sj.solve_wheel(WHEEL, bad, 4e3, 0.3, slip_angle=0.1)


class Drag(sj.AbstractForceTerm):
    """A resistance q r b [N] (q [Pa]) for the checks above."""

    pressure: jax.Array

    def forces(self, nodes):
        return sj.Resultants(motion_resistance=self.pressure * nodes.radius * 0.3)


def test_what_the_checks_remember_goes_with_the_parameters():
    """The eager checks remember per parameter object; a collected object's entries go
    with it, and the default models of bare terrains are bounded (16)."""
    import gc

    from snowjax._wheel import inputs, model

    before = set(inputs._CONCRETE)  # other tests' distributions still alive
    for _ in range(40):
        dist = sj.WongReece(jnp.asarray(0.43), jnp.asarray(0.32))
        snow = sj.WongSnow.thesis_fresh_snow()
        sj.solve_wheel(WHEEL, sj.ContactModel(snow, dist), 4e3, 0.3)
        sj.solve_wheel(WHEEL, snow, 4e3, 0.3)
        assert id(dist) in {k for k, _ in inputs._CONCRETE}
    del dist, snow
    gc.collect()
    assert set(inputs._CONCRETE) <= before  # every distribution here was collected
    assert len(model._MODELS) <= 16


def test_the_per_point_stresses_name_a_wrong_terrain():
    with pytest.raises(TypeError, match="snow must be a snowjax terrain, got float"):
        sj.shear_stress(0.1, 0.3, 0.2, WHEEL, 3.0)
    with pytest.raises(TypeError, match="snow must be a snowjax terrain"):
        sj.contact_forces(WHEEL, "snow", 0.3, 0.2)


def test_defaults_first_built_inside_jit_do_not_leak_tracers():
    """The default lateral law and a bare terrain's default model are built once and
    kept: first built inside `jax.jit`, they must hold concrete arrays, not tracers."""
    from snowjax._wheel import model, running

    running._default_lateral.cache_clear()
    snow = sj.WongSnow.thesis_fresh_snow()
    model._MODELS.clear()
    traced = jax.jit(lambda load: sj.solve_wheel(WHEEL, snow, load, 0.3, slip_angle=0.1))
    inside = traced(4e3).drawbar_pull
    eager = sj.solve_wheel(WHEEL, snow, 4e3, 0.3, slip_angle=0.1).drawbar_pull
    np.testing.assert_allclose(eager, inside, rtol=1e-12)
    assert not any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(
        (running._default_lateral(True), model._as_model(snow))))  # fmt: skip
