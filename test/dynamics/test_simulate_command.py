"""``gait-planner simulate`` and `gait_planner.cli.simulate.simulate`.

In process through `gait_planner.cli.main` (fast), plus one real process through the
installed console script: JSON keys and values, the readable table, pinned runs, and one
clear error line (exit code 2, no traceback) for every kind of bad input and for a step
without solution.
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from gait_planner import cli
from gait_planner.cli.simulate import simulate
from gait_planner.dynamics.free_motion import FreeMotionReport

REQUIRED_KEYS = {
    "energy_error_max", "linear_momentum_error_max", "angular_momentum_error_max",
    "constraint_violation_max", "newton_iterations_mean", "wall_time_s",
}
ALL_KEYS = {f.name for f in dataclasses.fields(FreeMotionReport)} | {"scene", "pinned"}


def run_cli(capsys, *args):
    code = cli.main(["simulate", *args])
    out, err = capsys.readouterr()
    return code, out, err


def test_json_output(capsys):
    code, out, err = run_cli(capsys, "--scene", "compass", "--steps", "300", "--dt", "0.01",
                             "--no-gravity", "--torques", "random", "--seed", "3", "--json")
    assert code == 0 and err == ""
    result = json.loads(out)
    assert REQUIRED_KEYS <= set(result) and set(result) == ALL_KEYS
    assert result["scene"] == "compass" and result["pinned"] is None
    assert (result["steps"], result["dt"], result["gravity"], result["torques"],
            result["seed"]) == (300, 0.01, False, "random", 3)
    assert result["linear_momentum_error_max"] <= 1e-10 * result["linear_momentum_scale"]
    assert result["angular_momentum_error_max"] <= 1e-10 * result["angular_momentum_scale"]
    assert result["constraint_violation_max"] <= 1e-12
    assert 1 <= result["newton_iterations_mean"] < 5
    assert result["wall_time_s"] > 0


def test_table_output(capsys):
    code, out, err = run_cli(capsys, "--scene", "walker3d", "--steps", "20", "--dt", "0.01")
    assert code == 0 and err == ""
    assert out.startswith("walker3d: 20 steps of 0.01 s, gravity on, torques zero")
    for label in ("energy error", "linear momentum error", "angular momentum error",
                  "constraint violation", "Newton iterations", "wall time"):
        assert label in out
    assert "{" not in out


def test_pinned_json(capsys):
    code, out, _ = run_cli(capsys, "--scene", "compass", "--steps", "500", "--dt", "0.005",
                           "--pin", "foot_r", "--json")
    assert code == 0
    result = json.loads(out)
    assert result["pinned"] == "foot_r" and result["gravity"] is True
    assert result["energy_error_max"] < 1e-2
    assert result["constraint_violation_max"] <= 1e-12


def test_simulate_function_is_json_ready():
    result = simulate("compass", 10, 0.01, True, "zero", 0)
    assert json.loads(json.dumps(result)) == result
    assert set(result) == ALL_KEYS


@pytest.mark.parametrize("args, says", [
    (["--scene", "nope", "--steps", "10", "--dt", "0.01"], "unknown scene 'nope'"),
    (["--scene", "../compass", "--steps", "10", "--dt", "0.01"], "bare names"),
    (["--scene", "compass", "--steps", "0", "--dt", "0.01"], "--steps: must be >= 1"),
    (["--scene", "compass", "--steps", "-3", "--dt", "0.01"], "--steps"),
    (["--scene", "compass", "--steps", "2.5", "--dt", "0.01"], "--steps: expected an integer"),
    (["--scene", "compass", "--steps", "10", "--dt", "0"], "--dt: must be a finite number > 0"),
    (["--scene", "compass", "--steps", "10", "--dt", "-0.01"], "--dt"),
    (["--scene", "compass", "--steps", "10", "--dt", "nan"], "--dt: must be a finite"),
    (["--scene", "compass", "--steps", "10", "--dt", "inf"], "--dt: must be a finite"),
    (["--scene", "compass", "--steps", "10", "--dt", "fast"], "--dt: expected a number"),
    (["--scene", "compass", "--steps", "10", "--dt", "0.01", "--pin", "heel"],
     "has no contact 'heel' (it has: foot_r, foot_l)"),
    (["--scene", "compass", "--steps", "10", "--dt", "0.01", "--seed", "-1"], "--seed"),
    (["--scene", "compass", "--steps", "10", "--dt", "0.01", "--torques", "big"], "--torques"),
    (["--steps", "10", "--dt", "0.01"], "--scene"),
])
def test_bad_input_gives_one_error_line(capsys, args, says):
    code, out, err = run_cli(capsys, *args)
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gait-planner: error: ")
    assert says in lines[0] and "Traceback" not in err


def test_step_without_solution_gives_one_error_line(capsys):
    code, out, err = run_cli(capsys, "--scene", "walker3d", "--steps", "200", "--dt", "0.05")
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("gait-planner: error: simulation failed: step 155")
    assert "reduce the time step" in lines[0]


@pytest.mark.parametrize("bad", [
    dict(steps=0), dict(steps=True), dict(dt=float("nan")), dict(dt=-1.0), dict(seed=-2),
    dict(torques="some"), dict(scene_name="missing"), dict(pin="nowhere"),
])
def test_simulate_function_rejects_bad_input(bad):
    kwargs = dict(scene_name="compass", steps=5, dt=0.01) | bad
    with pytest.raises(ValueError):
        simulate(**kwargs)


def console_script() -> Path:
    return Path(sys.executable).with_name("gait-planner")


@pytest.mark.skipif(not console_script().exists(), reason="console script not installed")
def test_console_script_process():
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    ok = subprocess.run(
        [str(console_script()), "simulate", "--scene", "compass", "--steps", "50", "--dt",
         "0.01", "--json"], capture_output=True, text=True, timeout=120, env=env)
    assert ok.returncode == 0, ok.stderr
    assert REQUIRED_KEYS <= set(json.loads(ok.stdout))
    bad = subprocess.run(
        [str(console_script()), "simulate", "--scene", "compass", "--steps", "5", "--dt",
         "nan"], capture_output=True, text=True, timeout=120, env=env)
    assert bad.returncode == 2 and bad.stdout == ""
    assert bad.stderr.strip().splitlines() == [
        "gait-planner: error: argument --dt: must be a finite number > 0, got 'nan' "
        "(see 'gait-planner --help')"]
