"""The `gait-planner` plan/run commands end to end on the compass (about a second): files,
summary, exit codes, and one-line errors for what the user has to fix."""

from __future__ import annotations

import json

import pytest

from gait_planner.cli import main


def test_run_plans_records_draws_and_compares(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    out = tmp_path / "compass.mcap"
    assert main(["run", "--scene", "compass", "--out", str(out), "--no-rrd"]) == 0
    text = capsys.readouterr().out
    assert out.is_file() and out.with_suffix(".png").is_file()
    assert "this plan: J = 1.31" in text and "the paper" in text
    assert "no display" in text


def test_plan_json_summary(tmp_path, capsys):
    out = tmp_path / "c.mcap"
    assert main(["plan", "--scene", "compass", "--out", str(out), "--json", "--no-rrd"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["success"] is True and data["scene"] == "compass"
    assert data["max_constraint_violation"] <= 1e-9
    assert data["mcap"] == str(out.resolve()) or data["mcap"] == str(out)


def test_failed_plan_exits_1_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "short.mcap"
    code = main(["plan", "--scene", "compass", "--max-time", "0.001", "--out", str(out),
                 "--no-rrd"])
    assert code == 1
    assert "time limit" in capsys.readouterr().out
    assert not out.exists()


def test_impossible_request_is_refused_in_one_line(tmp_path, capsys):
    out = tmp_path / "far.mcap"
    code = main(["plan", "--scene", "compass", "--step-length", "3", "--out", str(out),
                 "--no-rrd"])
    assert code == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert len(errors) == 1
    assert errors[0].startswith("gait-planner: error: step_length = 3.0 is outside the range")
    assert "(0, 2.000] m" in errors[0]
    assert not out.exists()


def test_user_errors_are_one_line(tmp_path, capsys):
    assert main(["plan", "--scene", "compass", "--out", str(tmp_path / "x.txt")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gait-planner: error: --out must name a .mcap file")
    assert main(["plan", "--scene", "no_such_scene", "--out", str(tmp_path / "x.mcap")]) == 2
    assert "gait-planner: error:" in capsys.readouterr().err


def test_prepare_compiles_marks_skips_and_refuses_unknown_scenes(capsys, tmp_path,
                                                                 monkeypatch):
    """In an empty cache: --default-only builds the default problem and plans it without
    marking the scene; a full prepare reports each problem built and marks it; the next
    skips it, --again does not."""
    from gait_planner.model.loader import load_scene
    from gait_planner.ocp.prepared import is_prepared

    monkeypatch.setenv("GAIT_PLANNER_CACHE", str(tmp_path / "cache"))
    assert main(["prepare", "--default-only", "compass"]) == 0
    out = capsys.readouterr().out
    assert "compass: per-node elements compiled to C; its default plan kept" in out
    assert "problem 1 of" not in out and not is_prepared(load_scene("compass"))
    assert main(["prepare", "compass"]) == 0
    out = capsys.readouterr().out
    assert "compass: problem 5 of 5 built (ground forms and gaits)" in out
    assert is_prepared(load_scene("compass"))
    assert main(["prepare", "compass"]) == 0
    assert capsys.readouterr().out == "compass: prepared already (--again prepares it anew)\n"
    assert main(["prepare", "--again", "compass"]) == 0
    assert "compass: problem 5 of 5 built" in capsys.readouterr().out
    assert main(["prepare", "no_such_scene"]) == 2
    assert "gait-planner: error:" in capsys.readouterr().err


def test_a_prepared_start_and_stop_are_repeated_warm_by_a_fresh_process(tmp_path):
    """`prepare` plans the scene's start from standing and its stop into the warm-start
    store; a fresh process's first `plan --from standing` and `--to standing` (a new
    Planner on that store) begin where those did and repeat them warm, in at most two
    iterations (walker3d from standing planned cold: 71; benchmarks/HISTORY.md)."""
    from gait_planner.cli.prepare import _plan_start_and_stop
    from gait_planner.model.loader import load_scene
    from gait_planner.ocp.settings import settings_for
    from gait_planner.ocp.solve import Planner
    from gait_planner.ocp.transition import standing_start
    from gait_planner.ocp.warm_starts import WarmStartStore
    from gait_planner.transitions import plan_transition

    scene = load_scene("walker2d")
    settings = settings_for(scene, compiled=True)
    prepared = Planner(library=WarmStartStore(tmp_path), pin=True)
    assert _plan_start_and_stop(prepared, scene, settings) == [True, True]
    fresh = Planner(library=WarmStartStore(tmp_path))
    for start, stop in ((standing_start(scene), False), (None, True)):
        result = plan_transition(fresh, scene, settings, start, stop=stop)
        assert result.success, result.message
        assert "warm: it began at this start" in result.settings["initial_guess"]
        assert result.stats.iterations <= 2, result.stats.iterations


def test_node_takes_the_ros_arguments_in_order(monkeypatch):
    import gait_planner.ros.node as node

    seen = []
    monkeypatch.setattr(node, "main", lambda args: seen.append(args) or 0)
    assert main(["node", "--ros-args", "-p", "output_dir:=runs", "-p", "max_solve_time:=30.0"]) == 0
    assert seen[0][1:] == ["--ros-args", "-p", "output_dir:=runs", "-p", "max_solve_time:=30.0"]
    assert main(["plan", "--scene", "compass", "--out", "x.mcap", "--bogus"]) == 2


def test_plan_refuses_a_negative_step_length_as_the_node_does(tmp_path, capsys):
    out = tmp_path / "back.mcap"
    assert main(["plan", "--scene", "compass", "--step-length", "-0.5", "--out", str(out),
                 "--no-rrd"]) == 2
    assert capsys.readouterr().err.endswith("gait-planner: error: step_length must be > 0 m, "
                                            "or 0 for the scene's default, got -0.5\n")
    assert not out.exists()


def test_call_refuses_a_bad_field_before_sending(capsys, monkeypatch):
    import gait_planner.ros.client as client

    monkeypatch.setattr(client.rclpy, "init", lambda **_: pytest.fail("rclpy started"))
    assert main(["call", "--step-length", "-0.5"]) == 2
    assert capsys.readouterr().err == ("gait-planner: error: step_length must be > 0 m, or 0 "
                                       "for the scene's default, got -0.5\n")
    assert main(["call", "--action", "--friction-coefficient", "nan"]) == 2
    assert "friction_coefficient must be > 0, or 0 for the scene's default, got nan" in (
        capsys.readouterr().err)
    assert main(["call", "--timeout", "-1"]) == 2
    assert "--timeout must be > 0 s, got -1.0" in capsys.readouterr().err


def test_call_options_are_the_request_fields_with_the_node_defaults(capsys):
    from gait_planner.request import FIELDS
    from gait_planner.ros.parameters import DECLARATIONS

    assert main(["call", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    for name in FIELDS:
        assert f"--{name.replace('_', '-')}" in text
    assert "--compile" not in text and "--no-rrd" not in text and "--mu" not in text
    assert f"default_scene, {DECLARATIONS['default_scene'][0]} unless set" in text
    assert f"max_solve_time, {DECLARATIONS['max_solve_time'][0]:g} s unless set" in text


@pytest.mark.parametrize("answer, line", [
    ({"status": "canceled", "success": False, "message": "stopped on request", "cost": 0.0},
     "canceled: stopped on request"),
    ({"status": "rejected", "success": False, "message": "busy: another plan is running"},
     "rejected: busy: another plan is running"),
    ({"status": "failed", "success": False, "message": "IPOPT: time limit", "iterations": 0},
     "failed: IPOPT: time limit"),
])
def test_call_prints_a_plan_that_was_not_made_as_its_status_and_reason(
        answer, line, capsys, monkeypatch):
    import gait_planner.ros.client as client

    sent = []
    monkeypatch.setattr(client, "call_plan_gait_action",
                        lambda fields, timeout: sent.append(fields) or answer)
    assert main(["call", "--action", "--steps", "2", "--cold-start"]) == 1
    assert capsys.readouterr().out == line + "\n"
    assert sent[0]["steps"] == 2 and sent[0]["cold_start"] is True
    assert main(["call", "--action", "--json"]) == 1
    assert json.loads(capsys.readouterr().out) == {
        key: answer[key] for key in ("status", "success", "message")}


# --- defaults and scenes from anywhere (helper "defaults") -------------------------------


def _compass_copy(folder, name: str = "my_compass", **changes):
    """A copy of the shipped compass under another file name, with `changes` applied."""
    import yaml

    from gait_planner.model.loader import load_scene

    data = yaml.safe_load(load_scene("compass").source)
    data.update(changes)
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def test_plan_takes_a_scene_file_from_anywhere(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = _compass_copy(tmp_path, "my copy", description="copied")
    out = tmp_path / "copy.mcap"
    assert main(["plan", "--scene", str(path), "--out", str(out), "--json", "--no-rrd"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["success"] and data["scene"] == "compass" and out.is_file()  # its own name
    assert main(["urdf", "my copy.yaml", "--out", "robot.urdf"]) == 0  # relative path
    assert (tmp_path / "robot.urdf").read_text().count("<link ") >= 2
    capsys.readouterr()
    assert main(["simulate", "--scene", "my copy.yaml", "--steps", "2", "--dt", "0.01",
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["scene"] == "compass"


@pytest.mark.parametrize("scene, words", [
    ("missing.yaml", "gait-planner: error: missing.yaml: no such scene file (not found at "),
    ("../compass", "or paths to a scene file ending in .yaml or .yml, got '../compass'"),
    ("bad.yaml", "gait-planner: error: bad.yaml: gravity: must be a number >= 0.0"),
])
def test_a_scene_that_cannot_be_used_is_named_with_the_rule(tmp_path, capsys, monkeypatch,
                                                            scene, words):
    monkeypatch.chdir(tmp_path)
    _compass_copy(tmp_path, "bad", gravity=-1.0)
    for command in (["plan", "--scene", scene, "--out", "x.mcap"], ["urdf", scene],
                    ["simulate", "--scene", scene, "--steps", "1", "--dt", "0.01"],
                    ["prepare", scene]):
        assert main(command) == 2, command
        err = capsys.readouterr().err
        assert words in err and err.count("error") == 1, (command, err)
    assert not (tmp_path / "x.mcap").exists()


def test_plan_starts_from_the_warm_start_store_unless_told_cold(tmp_path, capsys,
                                                               monkeypatch):
    """`plan` reads and adds to the warm-start store as the node does: a second process's
    plan of the same request starts at the first's optimum and ends there; --cold-start
    solves from the guess again and leaves the store as it was."""
    monkeypatch.setenv("GAIT_PLANNER_CACHE", str(tmp_path / "cache"))
    store = tmp_path / "cache" / "plans"

    def plan(*options: str) -> dict:
        out = tmp_path / f"c{len(list(tmp_path.glob('*.mcap')))}.mcap"
        assert main(["plan", "--scene", "compass", "--no-compile", "--out", str(out),
                     "--json", "--no-rrd", *options]) == 0
        return json.loads(capsys.readouterr().out)

    first = plan()
    (kept,) = store.glob("*.npz")
    written = kept.stat().st_mtime_ns
    second = plan()
    assert kept.stat().st_mtime_ns != written  # the second plan was added ...
    written = kept.stat().st_mtime_ns
    cold = plan("--cold-start")
    assert kept.stat().st_mtime_ns == written  # ... a cold one is not
    assert first["iterations"] > 3 and second["iterations"] <= 3
    assert second["cost_value"] == pytest.approx(first["cost_value"], rel=1e-6)
    assert cold["iterations"] == first["iterations"]
    assert cold["cost_value"] == pytest.approx(first["cost_value"], rel=1e-9)


@pytest.mark.slow  # compiles the compass into an empty cache: about 16 s on 2 cores
def test_plan_compiles_by_default_and_says_so_only_when_it_builds(tmp_path, capsys,
                                                                  monkeypatch):
    """A compile cache miss is announced with what is built and the last build's time; a
    hit prints no such line; --no-compile uses CasADi's derivatives."""
    monkeypatch.setenv("GAIT_PLANNER_CACHE", str(tmp_path / "cache"))
    runs = []
    for options in ([], [], ["--no-compile"]):
        out = tmp_path / f"c{len(runs)}.mcap"
        assert main(["plan", "--scene", "compass", "--out", str(out), "--json", "--no-rrd",
                     *options]) == 0
        captured = capsys.readouterr()
        runs.append((json.loads(captured.out), captured.err))
    (first, first_err), (second, second_err), (casadi, casadi_err) = runs
    assert "first time" not in first_err + second_err + casadi_err
    announced = [line for line in first_err.splitlines()
                 if line.startswith("-- building: compiling")]
    assert len(announced) == 1 and "derivative elements to C into" in announced[0]
    assert "roughly a minute for walker2d" in announced[0]  # no earlier build in this cache
    assert (tmp_path / "cache" / "last_build.txt").is_file()
    assert "compiling" not in second_err and "compiling" not in casadi_err
    assert first["derivatives"] == second["derivatives"] == "per-node elements compiled to C"
    assert casadi["derivatives"].startswith("CasADi")


def test_without_a_compiler_or_a_cache_the_plan_uses_casadi_and_says_why(tmp_path, capsys,
                                                                        monkeypatch):
    monkeypatch.setenv("GAIT_PLANNER_CACHE", str(tmp_path / "empty"))
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    out = tmp_path / "c.mcap"
    assert main(["plan", "--scene", "compass", "--out", str(out), "--json", "--no-rrd"]) == 0
    captured = capsys.readouterr()
    notes = [line for line in captured.err.splitlines() if "not compiled" in line]
    assert len(notes) == 1 and notes[0].startswith(
        "-- building with CasADi's derivatives (not compiled: no C compiler found")
    assert json.loads(captured.out)["success"]


def test_scene_from_urdf_takes_the_mirror_tolerance_its_refusal_names(example_robots, tmp_path,
                                                                      capsys):
    urdf = str(example_robots / "talos_data/robots/talos_reduced.urdf")
    command = ["scene", "from-urdf", urdf, "--package-dir", str(example_robots.parents[1]),
               "--out", str(tmp_path / "talos.yaml")]
    assert main(command) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--mirror-tolerance 0.06 accepts it" in err
    assert main(command + ["--mirror-tolerance", "0.06"]) == 0
    assert "--mirror-tolerance 0.06" in (tmp_path / "talos.yaml").read_text()


def test_plan_from_a_recordings_state_joins_the_gait(tmp_path, capsys):
    """`plan --from RUN.mcap:TIME`: from the state of a 3-half-cycle plan where its third
    half cycle begins (the first stance again, two steps on) the transition (two half
    cycles by default) joins the gait with twice the gait's J (the state is the gait's
    own, with its discrete momentum);
    from the middle of its first half cycle, where the right heel is in the air, the
    request is refused naming the contact."""
    from gait_planner.io.mcap_reader import read_plan_mcap
    from gait_planner.verify import verify_recording

    gait = tmp_path / "gait.mcap"
    assert main(["plan", "--scene", "walker2d", "--steps", "3", "--cold-start", "--out",
                 str(gait), "--no-rrd", "--json"]) == 0
    planned = json.loads(capsys.readouterr().out)
    rec = read_plan_mcap(gait)
    N = int(rec.metadata["half_cycle_nodes"]) - 1
    out = tmp_path / "from.mcap"
    assert main(["plan", "--scene", "walker2d", "--steps", "2", "--cold-start", "--from",
                 f"{gait}:{float(rec.times[2 * (N - 1)]) + 1e-9!r}", "--out", str(out), "--no-rrd",
                 "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["success"] and data["nodes"] == 4 * (N - 1) + 2
    assert data["cost_value"] == pytest.approx(2 * planned["cost_value"], rel=1e-5)
    assert verify_recording(out).ok
    code = main(["plan", "--scene", "walker2d", "--from", f"{gait}:{float(rec.times[N // 2])!r}",
                 "--out", str(tmp_path / "refused.mcap"), "--no-rrd"])
    assert code == 2
    assert "foot_r_heel is" in capsys.readouterr().err
    assert not (tmp_path / "refused.mcap").exists()
