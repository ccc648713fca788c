"""The node's background preparation (prepare_scenes) and its service
/gait_planner/preparation, in an empty compile cache: what is ready and what is not yet, with
the child's progress; a request for a ground form not yet prepared is answered with a plan
(its problem compiled for it) and a message saying so, never left hanging; closing the node
ends the child; a real child prepares the compass and marks it in the cache, and `gait-planner
call --preparation` says so."""

from __future__ import annotations

import subprocess
import sys

import pytest

from gait_planner.model.loader import load_scene
from gait_planner.ocp.prepared import is_prepared
from gait_planner.ros import preparation
from gait_planner.ros.node import PREPARATION_SERVICE, SERVICE
from gait_planner_msgs.srv import PlanGait, Preparation

pytestmark = pytest.mark.timeout(300)

CLI = "import sys; from gait_planner.cli import main; sys.exit(main())"
ANSWER = 240.0  # s, the longest a request may take here: compiling a compass problem and planning


@pytest.fixture
def ask(planner_node, make_node, executor, spin_until, tmp_path, monkeypatch):
    """``ask(**parameters)``: a node gait_planner on the compass in an empty compile cache,
    preparing it in the background, and a function calling one of its services."""
    monkeypatch.setenv("GAIT_PLANNER_CACHE", str(tmp_path / "cache"))

    def start(**parameters):
        node = planner_node(default_scene="compass", prepare_on_start=True,
                            prepare_scenes=["compass"], **parameters)
        client_node = make_node("preparation_client")
        executor.add_node(client_node)
        clients = {Preparation: client_node.create_client(Preparation, PREPARATION_SERVICE),
                   PlanGait: client_node.create_client(PlanGait, SERVICE)}

        def call(kind, timeout: float = 20.0, **fields):
            client = clients[kind]
            assert spin_until(client.service_is_ready, timeout=20)
            future = client.call_async(kind.Request(**fields))
            assert spin_until(future.done, timeout=timeout), f"no answer in {timeout} s"
            return future.result()
        return node, call
    return start


def test_a_request_before_its_scene_is_prepared_is_planned_and_says_so(
        ask, spin_until, monkeypatch):
    # a child that reports one step and then stands still: the compass stays unprepared
    monkeypatch.setattr(preparation, "COMMAND", (
        "sh", "-c", 'echo "$1: problem 1 of 5 built (ground forms and gaits)"; exec sleep 600',
        "sh"))
    node, call = ask()
    assert spin_until(lambda: call(Preparation).pending == [
        "compass: problem 1 of 5 built (ground forms and gaits)"], timeout=20)
    status = call(Preparation)
    assert not status.done and list(status.ready) == []
    assert status.message.startswith("ready: none; not yet: compass: problem 1 of 5"), status.message
    # stairs: a ground form the cache does not hold yet
    answer = call(PlanGait, timeout=ANSWER, step_height=0.03, output_name="stairs")
    assert answer.message, "an answer without a message"
    assert answer.success, answer.message
    assert "compass is not prepared yet" in answer.message
    child = node._preparation._child
    node.close()
    assert spin_until(lambda: child.poll() is not None, timeout=10), "the child outlived close"


@pytest.mark.slow  # 31 s: a real `gait-planner prepare compass` in an empty cache
def test_the_node_prepares_its_scenes_in_the_background_and_says_when_ready(ask, spin_until):
    node, call = ask()
    assert spin_until(lambda: call(Preparation).done, timeout=ANSWER), \
        call(Preparation).message
    status = call(Preparation)
    assert list(status.ready) == ["compass"] and list(status.pending) == []
    assert status.message == "ready: compass"
    assert is_prepared(load_scene("compass"))
    told = subprocess.run([sys.executable, "-c", CLI, "call", "--preparation"],
                          capture_output=True, text=True, timeout=60)
    assert (told.returncode, told.stdout) == (0, "ready: compass\n"), told.stderr
    answer = call(PlanGait, timeout=ANSWER, step_height=0.03, output_name="stairs")
    assert answer.success and "not prepared" not in answer.message, answer.message


def test_without_scenes_to_prepare_the_service_says_so(planner_node, make_node, executor,
                                                       spin_until):
    planner_node()  # prepare_on_start false: nothing in the background
    client_node = make_node("preparation_client")
    executor.add_node(client_node)
    client = client_node.create_client(Preparation, PREPARATION_SERVICE)
    assert spin_until(client.service_is_ready, timeout=20)
    future = client.call_async(Preparation.Request())
    assert spin_until(future.done, timeout=20)
    assert future.result().done and "no scene is prepared" in future.result().message
