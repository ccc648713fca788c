"""The node serving from a gait library (parameter gait_library): a request inside the
library's grid starts from the plans around it, one outside is planned as usual, and the
answer says which."""

from __future__ import annotations

import pytest

from gait_planner.gaitlib.grid import parse_grid
from gait_planner.gaitlib.index import Manifest, write_manifest
from gait_planner.gaitlib.worker import plan_point
from gait_planner.ros.node import SERVICE
from gait_planner_msgs.srv import PlanGait

pytestmark = pytest.mark.timeout(300)


def test_a_request_inside_the_library_is_answered_from_it(planner_node, make_node, executor,
                                                          spin_until, tmp_path):
    folder = tmp_path / "library"
    manifest = Manifest(scene="walker2d", gait="", grid="step_length=0.55/0.65", request={})
    write_manifest(folder, manifest)
    grid = parse_grid(manifest.grid)
    for i, start in zip(grid.indices(), (None, "p00")):
        assert plan_point(str(folder), manifest, grid.name(i), grid.values(i), start).status == "ok"
    planner_node(default_scene="walker2d", gait_library=str(folder))
    node = make_node("library_client")
    executor.add_node(node)
    client = node.create_client(PlanGait, SERVICE)
    assert spin_until(client.service_is_ready, 20)

    def call(**fields) -> PlanGait.Response:
        future = client.call_async(PlanGait.Request(**fields))
        assert spin_until(future.done, 240), "no answer"
        return future.result()

    inside = call(step_length=0.6, output_name="inside")
    assert inside.success, inside.message
    assert "started from the gait library library: p00 x 0.50, p01 x 0.50" in inside.message
    assert inside.iterations < 40
    outside = call(step_length=0.75, output_name="outside")
    assert outside.success, outside.message
    assert "not from the gait library library: step_length 0.75 is outside" in outside.message
