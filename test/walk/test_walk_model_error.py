"""A walker that is not the plan's model (`gait_planner.walk.model_error`): no difference
walks as the plain walk does, masses and inertias change by their drawn factors (the
robot's total mass within the spread), friction and contact stiffness reach every
contact, and a delayed command arrives the given number of steps late; the delay predictor
(`gait_planner.walk.predictor`) foresees the nominal walker exactly, and with it a 50 ms
delay is walked."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gait_planner.walk.model_error import DelayedTorque, ModelError

pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def walker2d_plan(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("model_error") / "w2.mcap"
    exe = Path(sys.executable).with_name("gait-planner")
    subprocess.run([str(exe), "plan", "--scene", "walker2d", "--out", str(out), "--no-rrd"],
                   check=True, capture_output=True)
    return out


def _model(recording: Path):
    from gait_planner.io.mcap_reader import read_plan_mcap
    from gait_planner.walk.mujoco_model import build_model
    from gait_planner.walk.reference import planned_joints, scene_of
    from gait_planner.walk.walk_plan import load_config

    rec = planned_joints(read_plan_mcap(recording))
    cfg = load_config()  # the walker `walk` builds
    sim = cfg["simulation"]
    return build_model(rec, scene_of(rec), float(rec.metadata.get("foot_half_width", 0.04575)),
                       sim["foot_sphere_radius"], sim["time_step"],
                       sim["contact_time_constant"], cfg["joints"]["kd"]).model


def test_no_difference_walks_as_the_plain_walk(walker2d_plan):
    from gait_planner.walk.walk_plan import walk

    plain = walk(walker2d_plan, 1)
    same = walk(walker2d_plan, 1, model_error=ModelError())
    assert same["model_error"] == {"differences": "none", "mass_factors": {}}
    for key in ("half_cycles_walked", "joint_rms_deg", "feedback_share", "torso_drift_m"):
        assert same[key] == plain[key]


def test_masses_friction_and_stiffness_reach_the_model(walker2d_plan):
    base = _model(walker2d_plan)
    changed = _model(walker2d_plan)
    error = ModelError(seed=3, mass_spread=0.1, friction=0.5, contact_time_constant=0.002)
    factors = error.apply(changed)
    assert len(factors) == base.nbody - 1 and all(0.9 <= f <= 1.1 for f in factors.values())
    for name, f in factors.items():
        b = base.body(name).id
        assert changed.body_mass[b] == pytest.approx(f * base.body_mass[b], rel=1e-12)
        assert np.allclose(changed.body_inertia[b], f * base.body_inertia[b], rtol=1e-12)
    total = changed.body_subtreemass[0] / base.body_subtreemass[0]  # by mj_setConst
    assert 0.9 <= total <= 1.1 and total != 1.0
    assert np.all(changed.geom_friction[:, 0] == 0.5)
    assert np.all(changed.geom_solref[:, 0] == 0.002)
    assert _model(walker2d_plan).body_mass.tolist() == base.body_mass.tolist()
    assert error.apply(_model(walker2d_plan)) == factors  # the seed decides


@given(steps=st.integers(0, 20), n=st.integers(1, 40))
def test_a_delayed_command_arrives_steps_late(steps, n):
    delayed = DelayedTorque(steps)
    commands = [np.array([float(k), -float(k)]) for k in range(n)]
    kp_q = np.array([0.25, 0.5])
    out = [delayed(c, kp_q) for c in commands]
    for k, torque in enumerate(out):
        assert np.array_equal(torque, commands[max(k - steps, 0)] - kp_q)


@pytest.mark.parametrize("fields, words", [
    ({"mass_spread": 1.0}, "mass_spread"), ({"friction": 0.0}, "friction"),
    ({"contact_time_constant": -1.0}, "contact_time_constant"),
    ({"torque_delay": float("nan")}, "torque_delay"),
])
def test_an_impossible_difference_is_refused(fields, words):
    with pytest.raises(ValueError, match=words):
        ModelError(**fields)


def test_the_predictor_foresees_the_nominal_walker_exactly(walker2d_plan):
    """On the plan's own walker the prediction is the simulation itself: the state
    `steps` steps after any step, under the commands in flight, to round-off."""
    import mujoco

    from gait_planner.walk.predictor import DelayPredictor

    model, steps, kp = _model(walker2d_plan), 7, 300.0
    data = mujoco.MjData(model)
    data.qpos[1] = 1.2  # the planar root's height: the walker falls onto its feet
    dofs = qpos = np.arange(3, model.nv)  # the planar root's 3 dofs come first
    delayed = DelayedTorque(steps)
    predictor = DelayPredictor(model, delayed, kp, dofs, qpos)
    rng = np.random.default_rng(5)
    states, predicted = [], []
    for _ in range(400):
        mujoco.mj_step1(model, data)
        predicted.append(predictor(data).qpos.copy())
        states.append(data.qpos.copy())
        command = rng.normal(0.0, 20.0, len(dofs)) + kp * data.qpos[qpos]
        data.qfrc_applied[:] = 0.0
        data.qfrc_applied[dofs] = delayed(command, kp * data.qpos[qpos])
        mujoco.mj_step2(model, data)
    assert np.array_equal(predicted[0], states[0])  # no command sent yet: nothing foreseen
    assert data.ncon > 0  # it ended on the ground
    for k in range(1, len(states) - steps):
        assert np.allclose(predicted[k], states[k + steps], rtol=0, atol=1e-12)


@pytest.mark.slow
def test_a_50_ms_delay_is_walked_with_the_predictor_and_not_without(walker2d_plan):
    from gait_planner.walk.walk_plan import load_config, walk

    late = ModelError(torque_delay=0.05)
    predicted = walk(walker2d_plan, 10, model_error=late)
    assert predicted["half_cycles_walked"] == 10, predicted["stopped"]
    # The delay costs feedback, and issue #40 item 2 sets it no bound (item 1's 40 % is
    # for prompt commands): walker2d's default walked with 26.9 % of the plan's torque
    # promptly and 41.5 % 50 ms late (2026-11-30; 39.2 % before the torso's place was
    # tracked). Bounded at 1.5 x item 1's target: a walk that completes only by far more
    # feedback fails.
    assert predicted["feedback_share"] <= 0.60
    blind = load_config()
    blind["delay"]["predict"] = False
    assert walk(walker2d_plan, 10, model_error=late, config=blind)["half_cycles_walked"] < 10
