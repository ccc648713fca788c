"""gait-planner walk: a recorded plan walked in MuJoCo by the reference controller.

Measured with config/walk.yaml as committed (2026-11-29, benchmarks/walk.py): walker2d's
default plan walks 10 of 10 half cycles (feedback share 0.24, joint RMS 0.61 deg), with the
plan's torques x0 1 (share 2.5), x0.5 4 (1.8); walker3d's walks 10 of 10 (share 0.33, joint
RMS 0.94 deg), x0 1, x0.5 2. The bounds below leave room for round-off in the plan (the
walk of a chaotic system: benchmarks/HISTORY.md gives the spread over simulation settings).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from gait_planner.cli import main

pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def walker2d_plan(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("walk") / "w2.mcap"
    exe = Path(sys.executable).with_name("gait-planner")
    subprocess.run([str(exe), "plan", "--scene", "walker2d", "--out", str(out)], check=True,
                   capture_output=True)
    return out


def _walks_ten_and_the_self_test_does_worse(plan: Path, share: float, touches: bool = True):
    from gait_planner.cli.walk import self_test
    from gait_planner.walk.walk_plan import walk

    full = walk(plan, 10)
    assert full["half_cycles_walked"] == 10 and full["stopped"] == "completed", full["stopped"]
    if not touches:
        assert full["unplanned_touches"] == [], full["unplanned_touches"]
    assert full["feedback_share"] < share and full["joint_rms_deg"] < 2.0
    assert len(full["torso_drift_m"]) == len(full["joint_rms_per_half_cycle_deg"]) == 10
    rows = self_test(str(plan), 10, full)
    zero = next(r for r in rows if r["torque_scale"] == 0)
    assert zero["half_cycles_walked"] < full["half_cycles_walked"]
    assert all(r["worse"] for r in rows)


@pytest.mark.slow
def test_walker2d_default_plan_walks_and_the_self_test_does_worse(walker2d_plan):
    _walks_ten_and_the_self_test_does_worse(walker2d_plan, 0.3)


@pytest.mark.slow
def test_walker3d_human_posture_plan_walks_and_the_self_test_does_worse(tmp_path):
    """The human posture (a stance knee of at most 20 deg) walked 7 of 10 with a hip losing
    its pitch until foot placement and swing height moved the whole swing leg (2026-11-29:
    10 of 10, feedback 32 %)."""
    out = tmp_path / "human.mcap"
    exe = Path(sys.executable).with_name("gait-planner")
    subprocess.run([str(exe), "plan", "--scene", "walker3d", "--posture", "human", "--out",
                    str(out)], check=True, capture_output=True)
    _walks_ten_and_the_self_test_does_worse(out, 0.4)


@pytest.mark.slow
def test_walker3d_default_plan_walks_and_the_self_test_does_worse(tmp_path):
    """The issue's target: ten half cycles with the feedback adding at most 40 %; and the
    feet touch the ground nowhere the plan does not (the heel struck 15-16 ms early four times
    in ten half cycles until the swing height aimed 1 cm above the plan's mid-swing,
    config/walk.yaml placement.swing_margin; no touch with 0.5-2 cm)."""
    out = tmp_path / "w3.mcap"
    exe = Path(sys.executable).with_name("gait-planner")
    subprocess.run([str(exe), "plan", "--scene", "walker3d", "--out", str(out)], check=True,
                   capture_output=True)
    _walks_ten_and_the_self_test_does_worse(out, 0.4, touches=False)


def test_one_half_cycle_of_walker2d_is_walked_and_recorded(walker2d_plan, tmp_path, capsys):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out = tmp_path / "walk.mcap"
    assert main(["walk", str(walker2d_plan), "--steps", "1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "walked 1 of 1 half cycles" in text and "completed" in text
    # the stance forefoot creeps in MuJoCo's soft friction (`walk.slides`): 7.7 mm here
    # on 2026-11-30, at a tenth of its cone
    assert "largest foot slide" in text and "foot_r_forefoot standing" in text
    with out.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        decoded = [(c.topic, m) for _, c, _, m in reader.iter_decoded_messages()]
        meta = {r.name: r.metadata for r in reader.iter_metadata()}
    topics = {t for t, _ in decoded}
    assert topics == {"/walk/joint_states", "/walk/feedforward", "/walk/feedback",
                      "/walk/contact_forces"}
    states = [m for t, m in decoded if t == "/walk/joint_states"]
    # 200 Hz of simulated time over the plan's 0.585 s, which the walker's pace
    # (`walk.clock`) stretches or shrinks a little
    last = states[-1].header.stamp.sec + 1e-9 * states[-1].header.stamp.nanosec
    assert len(states) == round(last / 0.005) + 1 and abs(last - 0.585) < 0.03
    assert list(states[0].name)[0] == "hip_r"
    ff = [m for t, m in decoded if t == "/walk/feedforward"]
    fb = [m for t, m in decoded if t == "/walk/feedback"]
    k = 50  # the recorded torque is the sum of its parts
    assert max(abs(a - b - c) for a, b, c in zip(states[k].effort, ff[k].effort,
                                                 fb[k].effort)) < 1e-9
    weight = sum(sum(f.z for f in m.forces) for t, m in decoded if t == "/walk/contact_forces")
    assert weight / len(states) > 300  # the ground carries the walker (about 530 N)
    assert meta["gait_planner.walk"]["half_cycles_walked"] == "1"


def test_a_broken_recording_gets_a_clear_error(tmp_path, walker2d_plan, capsys):
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(walker2d_plan.read_bytes()[:2000])
    assert main(["walk", str(broken)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gait-planner: error: ") and str(broken) in err
    assert main(["walk", str(tmp_path / "missing.mcap")]) == 2
    assert "no such recording" in capsys.readouterr().err


def test_a_replanned_walks_deadline_outside_its_range_is_refused(capsys):
    for bad in ("0", "-1", "nan", "11", "soon"):
        assert main(["walk", "--replan", "walker2d", "--deadline", bad]) == 2
        assert "argument --deadline" in capsys.readouterr().err
    assert main(["walk", "any.mcap", "--deadline", "2"]) == 2
    assert "only with --replan" in capsys.readouterr().err


def test_a_scene_without_feet_is_refused(tmp_path, capsys):
    out = tmp_path / "compass.mcap"
    exe = Path(sys.executable).with_name("gait-planner")
    subprocess.run([str(exe), "plan", "--scene", "compass", "--out", str(out)], check=True,
                   capture_output=True)
    assert main(["walk", str(out)]) == 2
    err = capsys.readouterr().err
    assert "scene 'compass'" in err and "heel and forefoot" in err


def test_a_bad_controller_config_names_the_key(tmp_path):
    from gait_planner.walk.walk_plan import CONFIG, load_config

    assert load_config()["joints"]["kp"] > 0
    bad = tmp_path / "walk.yaml"
    bad.write_text(CONFIG.read_text().replace("kd: 100.0", "kd: -1"))
    with pytest.raises(ValueError, match=r"walk.yaml: torso.kd must be a finite number >= 0"):
        load_config(bad)
    bad.write_text(CONFIG.read_text().replace("noslip_iterations: 10", "noslip_iterations: 2.5"))
    with pytest.raises(ValueError, match=r"simulation.noslip_iterations must be a whole number"):
        load_config(bad)
    bad.write_text(CONFIG.read_text().replace("rate_max: 1.5", "rate_max: 0.9"))
    with pytest.raises(ValueError, match=r"walk.yaml: clock.rate_min and clock.rate_max must"):
        load_config(bad)


def test_a_recording_of_ten_half_cycles_is_walked_as_recorded(tmp_path):
    """`plan --steps 10` records the joined half cycles; the walk's reference is those
    nodes (joined from the first half cycle), so it walks on past the first join."""
    import dataclasses

    from gait_planner.io.mcap_reader import read_plan_mcap
    from gait_planner.walk.reference import Reference
    from gait_planner.walk.walk_plan import walk

    out = tmp_path / "w2x10.mcap"
    exe = Path(sys.executable).with_name("gait-planner")
    subprocess.run([str(exe), "plan", "--scene", "walker2d", "--steps", "10", "--no-rrd",
                    "--out", str(out)], check=True, capture_output=True)
    rec = read_plan_mcap(out)
    ref = Reference.from_recording(rec, 10)
    assert len(ref.times) == rec.n_nodes == 392 and ref.active == tuple(rec.active_contacts)
    for walked, recorded in ((ref.times, rec.times), (ref.q, rec.q), (ref.angles, rec.positions),
                             (ref.rates, rec.velocities), (ref.efforts, rec.effort)):
        assert abs(walked - recorded).max() < 1e-9
    assert Reference.from_recording(rec, 12).times[-1] > rec.times[-1]  # more than recorded
    wrong = dataclasses.replace(rec, metadata=dict(rec.metadata, half_cycle_nodes="40"))
    with pytest.raises(ValueError, match=r"392 nodes are not 10 joined half cycles .* '40'"):
        Reference.from_recording(wrong, 10)
    result = walk(out, 2)
    assert result["half_cycles_walked"] == 2 and result["stopped"] == "completed"


def test_walk_takes_a_controller_file_and_names_what_is_wrong(walker2d_plan, tmp_path, capsys):
    from gait_planner.walk.walk_plan import CONFIG

    mine = tmp_path / "mine.yaml"
    mine.write_text(CONFIG.read_text().replace("tilt: 35.0", "tilt: 0.05"))
    assert main(["walk", str(walker2d_plan), "--steps", "2", "--config", str(mine),
                 "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["stopped"].startswith("fall: torso tilted")  # 0.05 deg: in the first 0.2 s
    broken = tmp_path / "broken.yaml"
    broken.write_text("joints: [kp: 1")
    assert main(["walk", str(walker2d_plan), "--config", str(broken)]) == 2
    assert "broken.yaml: not a YAML file" in capsys.readouterr().err
    assert main(["walk", str(walker2d_plan), "--config", str(tmp_path / "none.yaml")]) == 2
    assert "cannot read" in capsys.readouterr().err
