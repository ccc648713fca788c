"""The node's parameters over real rclpy: declared with type, range and description, refused
with a reason when set to a bad value at run time, read from config/gait_planner.yaml by
`gait-planner node --params-file`; and the removal of stale temporary files at start."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from rcl_interfaces.msg import ParameterType
from rclpy.parameter import Parameter, parameter_value_to_python
from rclpy.parameter_client import AsyncParameterClient

pytestmark = pytest.mark.timeout(120)

REPO = Path(__file__).resolve().parents[2]
GAIT_PLANNER = str(Path(sys.executable).parent / "gait-planner")
SHIPPED = REPO / "config" / "gait_planner.yaml"


@pytest.fixture
def parameters(planner_node, make_node, executor, spin_until):
    """A node gait_planner (writing to tmp_path), a parameter client of it and a helper that
    waits for a future."""
    planner_node()
    node = make_node("parameter_test_client")
    executor.add_node(node)
    client = AsyncParameterClient(node, "gait_planner")

    def wait(future):
        assert spin_until(future.done, 10), "no answer from the parameter services"
        return future.result()

    assert spin_until(client.services_are_ready, 20), "parameter services not discovered"
    return client, wait


def _values(client, wait, names):
    answer = wait(client.get_parameters(names))
    return {name: parameter_value_to_python(value) for name, value in zip(names, answer.values)}


@pytest.fixture
def parameters_of_process(make_node, executor, spin_until):
    """``parameters_of_process(process, names)``: the values of `names` of the node
    gait_planner run by `process` (waits for it to come up)."""
    node = make_node("parameter_process_client")
    executor.add_node(node)
    client = AsyncParameterClient(node, "gait_planner")

    def read(process: subprocess.Popen, names: list[str]) -> dict:
        assert spin_until(lambda: client.services_are_ready() or process.poll() is not None,
                          60), "the node did not come up"
        assert process.poll() is None, "the node ended"
        future = client.get_parameters(names)
        assert spin_until(future.done, 10)
        return {name: parameter_value_to_python(value)
                for name, value in zip(names, future.result().values)}

    return read


def test_parameters_are_declared_with_type_range_and_description(parameters):
    client, wait = parameters
    names = ["default_scene", "output_dir", "allowed_output_dirs", "max_solve_time",
             "compile_derivatives", "feedback_every", "prepare_on_start", "warm_start_store",
             "scene_dirs", "gait_library", "prepare_scenes"]
    described = {d.name: d for d in wait(client.describe_parameters(names)).descriptors}
    assert all(described[name].description for name in names)
    assert described["max_solve_time"].type == ParameterType.PARAMETER_DOUBLE
    assert described["max_solve_time"].floating_point_range[0].to_value == 3600.0
    assert described["feedback_every"].integer_range[0].from_value == 1
    assert described["allowed_output_dirs"].read_only
    assert described["compile_derivatives"].type == ParameterType.PARAMETER_BOOL
    assert described["prepare_on_start"].read_only
    assert described["warm_start_store"].read_only
    assert described["gait_library"].read_only
    assert described["prepare_scenes"].read_only
    assert described["scene_dirs"].type == ParameterType.PARAMETER_STRING_ARRAY
    assert described["scene_dirs"].read_only


def test_the_former_name_of_the_warm_start_store_still_turns_it_off(planner_node):
    assert planner_node(warm_start_store=True)._planner.library is not None
    assert planner_node(warm_start_store=True, plan_library=False)._planner.library is None


def test_the_default_scene_is_built_at_start_when_asked(planner_node):
    """prepare_on_start: the default request's problem exists before the first request."""
    node = planner_node(default_scene="compass", prepare_on_start=True)
    assert len(node._planner._built) == 1
    assert not planner_node(default_scene="compass")._planner._built


@pytest.mark.parametrize("name, value, words", [
    ("max_solve_time", -1.0, "out of range"),
    ("max_solve_time", 0.0, "must be > 0"),
    ("max_solve_time", "fast", "type"),
    ("feedback_every", 0, "out of range"),
    ("default_scene", "no_such_scene", "not a known scene; available: compass"),
    ("output_dir", "/etc/gait_planner", "outside the allowed folders"),
    ("output_dir", "{tmp}/a_file/runs", "is not a folder"),
    ("allowed_output_dirs", ["/"], "read-only"),
    ("scene_dirs", ["/"], "read-only"),
])
def test_bad_values_are_refused_with_a_reason(parameters, tmp_path,
                                              name, value, words):
    client, wait = parameters
    (tmp_path / "a_file").write_text("not a folder")
    if isinstance(value, str):
        value = value.format(tmp=tmp_path)
    before = _values(client, wait, [name])
    result = wait(client.set_parameters([Parameter(name, value=value)])).results[0]
    assert not result.successful and words in result.reason, result.reason
    assert _values(client, wait, [name]) == before


def test_good_values_are_taken(parameters, tmp_path):
    client, wait = parameters
    wanted = {"max_solve_time": 12.5, "default_scene": "compass",
              "output_dir": str(tmp_path / "new" / "runs"), "feedback_every": 5}
    results = wait(client.set_parameters(
        [Parameter(k, value=v) for k, v in wanted.items()])).results
    assert all(r.successful for r in results), [r.reason for r in results]
    assert _values(client, wait, list(wanted)) == wanted


def test_the_shipped_params_file_is_read_and_overridden_by_ros_args(
        node_process, parameters_of_process, tmp_path):
    shipped = yaml.safe_load(SHIPPED.read_text())["gait_planner"]["ros__parameters"]
    process = node_process("--params-file", "config/gait_planner.yaml", "--ros-args",
                           "-p", f"output_dir:={tmp_path}",
                           "-p", f"allowed_output_dirs:=['{tmp_path}']",
                           "-p", "prepare_scenes:=['']")  # no background preparation
    values = parameters_of_process(process, list(shipped))
    assert values == {**shipped, "output_dir": str(tmp_path),
                      "allowed_output_dirs": [str(tmp_path)], "prepare_scenes": [""]}


@pytest.mark.parametrize("content, words", [
    ("gait_planner:\n  ros__parameters:\n    max_solve_time: -5.0\n", "max_solve_time"),
    ("gait_planner:\n  ros__parameters:\n    max_solve_time: 60\n", "expecting type 'DOUBLE'"),
    ("gait_planner:\n  ros__parameters:\n    output_dir: /etc\n", "outside the allowed"),
    (None, "is not a file"),
])
def test_a_bad_params_file_stops_the_node_with_the_reason(ros_domain_id, tmp_path,
                                                          content, words):
    path = tmp_path / "params.yaml"
    if content is not None:
        path.write_text(content)
    done = subprocess.run([GAIT_PLANNER, "node", "--params-file", str(path)], cwd=tmp_path,
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr.startswith("gait-planner: error:") and words in done.stderr, done.stderr


def test_node_help_names_the_params_file():
    done = subprocess.run([GAIT_PLANNER, "node", "--help"], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0 and "--params-file YAML" in done.stdout


def test_stale_temporary_files_are_removed_at_start(planner_node, tmp_path):
    ended = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                           capture_output=True, text=True, check=True)
    dead = tmp_path / f".walk.mcap.{int(ended.stdout)}.0123456789ab.tmp"
    alive = tmp_path / f".walk.rrd.{os.getpid()}.0123456789ab.tmp"
    other = tmp_path / ".notes.tmp"
    for path in (dead, alive, other):
        path.write_bytes(b"half")
    planner_node()
    assert not dead.exists()
    assert alive.exists() and other.exists()


@pytest.mark.parametrize("given", [["--params-file", str(SHIPPED)], [f"--params-file={SHIPPED}"]])
def test_the_command_line_puts_the_params_file_before_the_ros_arguments(monkeypatch, given):
    import gait_planner.ros.node as node
    from gait_planner.cli import main

    seen = []
    monkeypatch.setattr(node, "main", lambda args: seen.append(args) or 0)
    assert main(["node", *given, "--ros-args", "-p", "output_dir:=runs"]) == 0
    assert seen[0][1:] == ["--ros-args", "--params-file", str(SHIPPED), "--",
                           "--ros-args", "-p", "output_dir:=runs"]


def test_scene_dirs_add_scene_folders_whose_scenes_requests_name_by_bare_name(
        planner_node, tmp_path):
    """A scene file in a folder of scene_dirs is planned by its bare name (also as the
    default scene); a path in a request is refused, naming both ways to add a folder."""
    from gait_planner.model.loader import load_scene
    from gait_planner_msgs.srv import PlanGait

    folder = tmp_path / "my_scenes"
    folder.mkdir()
    (folder / "my_compass.yaml").write_text(load_scene("compass").source)
    node = planner_node(scene_dirs=[str(folder), str(tmp_path / "missing")],
                        default_scene="my_compass")
    answer = PlanGait.Response()
    node._plan_into(PlanGait.Request(scene="", output_name="mine"), answer)  # the default
    assert answer.success, answer.message
    assert (tmp_path / "mine.mcap").is_file()
    refused = PlanGait.Response()
    node._plan_into(PlanGait.Request(scene=str(folder / "my_compass.yaml")), refused)
    assert not refused.success and "bare names" in refused.message
    assert "scene_dirs" in refused.message and "GAIT_PLANNER_SCENE_PATH" in refused.message


def test_a_scene_dirs_entry_that_is_a_file_stops_the_node(planner_node, tmp_path):
    (tmp_path / "a_file").write_text("not a folder")
    with pytest.raises(Exception, match="scene_dirs entry .*a_file.* is not a folder"):
        planner_node(scene_dirs=[str(tmp_path / "a_file")])
