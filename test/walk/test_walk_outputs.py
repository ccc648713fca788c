"""gait-planner walk --out/--rrd: the walk's rerun view, read back with rerun's own reader.

walker2d's default plan walked 2 half cycles: the .rrd holds the simulated and the planned
walker, the ground forces of both (each averaging the walker's weight over the walk), the
plots and the errors per half cycle of the summary; the simulated feet drawn from the torso
pose and the joint angles are where MuJoCo has them. A missing folder is said before the walk,
an unwritable target after it (the walk's progress said before), and neither leaves a file
behind.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gait_planner.cli import main

pytest.importorskip("mujoco")
pytest.importorskip("rerun")

ENTITIES = ("/world/ground", "/world/sim/torso", "/world/sim/foot_l", "/world/sim/skeleton",
            "/world/sim/forces", "/world/plan/torso", "/world/plan/foot_r",
            "/world/plan/skeleton", "/world/plan/forces", "/plots/joint_angle/hip_r/sim",
            "/plots/joint_angle/knee_l/plan", "/plots/joint_torque/ankle_r/feedforward",
            "/plots/joint_torque/ankle_r/feedback", "/plots/ground_force/foot_l_heel/sim",
            "/plots/ground_force/foot_r_forefoot/plan", "/plots/half_cycle/joint_rms",
            "/plots/half_cycle/torso_drift/y", "/plots/half_cycle/foot_placement",
            "/plots/half_cycles/joint_angle_hip_right", "/walk")


@pytest.fixture(scope="module")
def walked(tmp_path_factory) -> tuple[Path, dict, Path]:
    """(the plan, the --json summary, the .rrd) of walker2d's plan walked 2 half cycles."""
    folder = tmp_path_factory.mktemp("walk_outputs")
    plan = folder / "w2.mcap"
    exe = Path(sys.executable).with_name("gait-planner")
    subprocess.run([str(exe), "plan", "--scene", "walker2d", "--out", str(plan)], check=True,
                   capture_output=True)
    done = subprocess.run([str(exe), "walk", str(plan), "--steps", "2", "--json", "--out",
                           str(folder / "walk.mcap"), "--rrd", str(folder / "walk.rrd")],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return plan, json.loads(done.stdout), folder / "walk.rrd"


def _rows(rrd: Path) -> dict[str, list[dict]]:
    """Entity path -> the temporal rows of the recording (time in s), in time order."""
    import pyarrow as pa
    from rerun.chunk import RrdReader

    out: dict[str, list[dict]] = {}
    for chunk in RrdReader(rrd).stream():
        if chunk.is_static:
            out.setdefault(chunk.entity_path, [])
            continue
        batch = chunk.to_record_batch()
        times = batch.column("time").cast(pa.int64()).to_numpy() * 1e-9
        rest = batch.drop_columns(["time"]).to_pylist()
        out.setdefault(chunk.entity_path, []).extend(dict(r, time=t) for t, r in zip(times, rest))
    return {k: sorted(v, key=lambda r: r["time"]) for k, v in out.items()}


def test_both_files_are_written_and_the_rrd_holds_its_entities(walked):
    _, summary, rrd = walked
    from rerun.chunk import RrdReader

    assert summary["half_cycles_walked"] == 2 and "series" not in summary
    assert summary["rrd"] == str(rrd) and Path(summary["out"]).is_file()
    assert sorted(p.name for p in rrd.parent.iterdir()) == ["w2.mcap", "w2.rrd", "walk.mcap",
                                                         "walk.rrd"]
    rows = _rows(rrd)
    missing = [e for e in ENTITIES if e not in rows]
    assert not missing, missing
    assert RrdReader(rrd).blueprints(), "the layout is part of the file"
    drift = [r["Scalars:scalars"][0] for r in rows["/plots/half_cycle/torso_drift/x"]]
    assert drift == pytest.approx([d[0] for d in summary["torso_drift_m"]], abs=1e-6)
    rms = [r["Scalars:scalars"][0] for r in rows["/plots/half_cycle/joint_rms"]]
    assert rms == pytest.approx(summary["joint_rms_per_half_cycle_deg"], abs=1e-6)
    assert len(rms) == 2 and 0 < max(rms) <= summary["joint_max_deg"]


def test_the_ground_carries_both_walkers_and_the_plan_holds_its_contacts(walked):
    """Each walker's ground forces, averaged over the walk, are its weight; the planned
    arrows stand on the contacts the joined plan holds (mirrored: the partner foot's in
    the second half cycle)."""
    plan, _, rrd = walked
    from gait_planner.io.mcap_reader import read_plan_mcap
    from gait_planner.viz.rerun_view import FORCE_SCALE
    from gait_planner.walk.reference import Reference

    ref = Reference.from_recording(read_plan_mcap(plan), 2)
    weight = 9.81 * sum(b.mass for b in ref.scene.bodies)
    rows = _rows(rrd)
    for entity in ("/world/sim/forces", "/world/plan/forces"):
        t = np.array([r["time"] for r in rows[entity]])
        fz = np.array([sum(v[2] for v in r["Arrows3D:vectors"]) / FORCE_SCALE
                       for r in rows[entity]])
        assert np.trapezoid(fz, t) / (t[-1] - t[0]) == pytest.approx(weight, rel=0.05), entity
    plan_rows = rows["/world/plan/forces"]
    assert len(plan_rows) == len(ref.times)
    for m, row in enumerate(plan_rows):
        held = {label.split(":")[0] for label in row["Arrows3D:labels"]}
        assert held and held <= set(ref.active[m]), (m, held, ref.active[m])
    assert {c for a in ref.active for c in a} == {c.name for c in ref.scene.contacts}


def test_the_simulated_feet_are_drawn_where_mujoco_has_them(walked):
    """The simulated bodies come from the torso pose and joint angles through the planner's
    kinematics; their contact points meet the force arrows' origins (MuJoCo's positions)."""
    plan, _, rrd = walked
    from gait_planner.io.mcap_reader import Transform, read_plan_mcap
    from gait_planner.walk.reference import scene_of

    scene = scene_of(read_plan_mcap(plan))
    rows = _rows(rrd)
    feet = {b: rows[f"/world/sim/{b}"] for b in {c.body for c in scene.contacts}}
    checked = 0
    for n, row in enumerate(rows["/world/sim/forces"]):
        for label, origin in zip(row["Arrows3D:labels"], row["Arrows3D:origins"]):
            contact = scene.contact(label.split(":")[0])
            pose = feet[contact.body][n]
            assert pose["time"] == row["time"]
            T = Transform("world", contact.body, 0, np.array(pose["Transform3D:translation"][0]),
                          np.array(pose["Transform3D:quaternion"][0])).matrix()
            point = T[:3, :3] @ np.asarray(scene.body(contact.body).points[contact.point])
            # 1 um: walk()'s series are all of one state, and rerun keeps float32 (1.1e-7 m
            # at most measured); a step's lag (0.5 ms) is over 0.5 mm at walking speed, a
            # wrong angle order or sign centimetres
            assert np.linalg.norm(T[:3, 3] + point - origin) < 1e-6, (n, label)
            checked += 1
    assert checked > 100


def test_unwritable_outputs_are_refused_clearly(walked, tmp_path, capsys):
    plan, _, _ = walked
    missing = tmp_path / "no" / "walk.rrd"
    assert main(["walk", str(plan), "--rrd", str(missing)]) == 2
    assert capsys.readouterr().err == (f"gait-planner: error: cannot write {missing}: no folder "
                                       f"{missing.parent}\n")
    folder = tmp_path / "a_folder.rrd"  # the target is a folder: the rename fails
    folder.mkdir()
    assert main(["walk", str(plan), "--steps", "1", "--rrd", str(folder)]) == 2
    progress, err = capsys.readouterr().err.split("\n", 1)  # the walk was done
    assert progress == "-- walking (1 of 1 half cycles done)"
    assert err.startswith(f"gait-planner: error: cannot write {folder}: ") and "rrd" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_folder.rrd"]  # no temporary file
    same = tmp_path / "walk.out"
    assert main(["walk", str(plan), "--out", str(same), "--rrd", str(same)]) == 2
    assert "--out and --rrd name the same file" in capsys.readouterr().err
