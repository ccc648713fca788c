"""The views draw the ground a plan was made for (issue #26): the solid ground of
`gait_planner.io.urdf.ground_boxes` (a slab under a ramp, a box per stair tread), its URDF,
the rerun view's grid on it and the MuJoCo walk's ground; level ground as before."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.io.mcap_writer import write_plan_mcap
from gait_planner.io.urdf import (GROUND_HALF_WIDTH, GROUND_THICKNESS, ground_boxes,
                                  ground_to_urdf)
from gait_planner.model.ground import Ground

LEVEL = Ground(riser=0.44, tread=0.63)  # as a level plan records it: its stair fields unused
RAMP = Ground(slope=10.0, riser=0.44, tread=0.63)
UP = Ground(step_height=0.15, riser=0.44, tread=0.63)
DOWN = Ground(step_height=-0.15, riser=0.44, tread=0.63)


def _top_corners(box) -> np.ndarray:
    """(2, 3) the top face's front and back edge midpoints (y = 0) of a `GroundBox`."""
    p = box.pitch
    axis_x = np.array([math.cos(p), 0.0, -math.sin(p)])
    axis_z = np.array([math.sin(p), 0.0, math.cos(p)])
    top = np.array(box.centre) + 0.5 * box.size[2] * axis_z
    return np.array([top - 0.5 * box.size[0] * axis_x, top + 0.5 * box.size[0] * axis_x])


@pytest.mark.parametrize("ground", [LEVEL, RAMP])
def test_a_plane_is_one_slab_whose_top_is_the_ground(ground):
    (box,) = ground_boxes(ground, -1.0, 2.0)
    corners = _top_corners(box)
    np.testing.assert_allclose(corners[:, 0], [-1.0, 2.0], atol=1e-12)
    np.testing.assert_allclose(corners[:, 2], ground.height(corners[:, 0]), atol=1e-12)
    assert box.size[1:] == (2 * GROUND_HALF_WIDTH, GROUND_THICKNESS)
    assert box.pitch == pytest.approx(-math.radians(ground.slope))


@pytest.mark.parametrize("ground", [UP, DOWN])
def test_stairs_are_a_box_per_tread_from_its_height_down(ground):
    boxes = ground_boxes(ground, -0.5, 1.0)
    assert len(boxes) == 3  # treads -1 (x from -0.82 m), 0 and 1 (to 1.07 m)
    fronts = [b.centre[0] + b.size[0] / 2 for b in boxes]
    np.testing.assert_allclose(fronts, [ground.riser - ground.tread, ground.riser,
                                        ground.riser + ground.tread])
    tops = [b.centre[2] + b.size[2] / 2 for b in boxes]
    np.testing.assert_allclose(tops, ground.height([b.centre[0] for b in boxes]))
    bottoms = [b.centre[2] - b.size[2] / 2 for b in boxes]
    np.testing.assert_allclose(bottoms, min(tops) - GROUND_THICKNESS)
    assert all(b.pitch == 0.0 and b.size[0] == ground.tread for b in boxes)


def test_the_ground_urdf_loads_in_mujoco_with_its_boxes():
    mujoco = pytest.importorskip("mujoco")
    for ground in (RAMP, UP):
        text = ground_to_urdf(ground, -0.5, 1.2)
        link = ET.fromstring(text).find("link")
        boxes = ground_boxes(ground, -0.5, 1.2)
        assert len(link.findall("collision")) == len(link.findall("visual")) == len(boxes)
        model = mujoco.MjModel.from_xml_string(text)  # the collision boxes (visuals dropped)
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        np.testing.assert_allclose(data.geom_xpos, [b.centre for b in boxes], atol=1e-12)
        np.testing.assert_allclose(model.geom_size, [0.5 * np.array(b.size) for b in boxes])
        rpy = link.find("collision/origin").get("rpy").split()
        assert float(rpy[1]) == pytest.approx(-math.radians(ground.slope))


# ------------------------------------------------------------------ the rerun view


def _static(rrd, entity: str, component: str):
    from rerun.chunk import RrdReader

    for chunk in RrdReader(rrd).stream():
        if chunk.entity_path == entity and chunk.is_static:
            batch = chunk.to_record_batch()
            column = next(n for n in batch.schema.names if n.endswith(component))
            return batch.column(column).to_pylist()[0]
    return None


@pytest.fixture(scope="module")
def views(make_result, tmp_path_factory):
    """ground -> a saved .rrd of the synthetic walker3d result made on that ground."""
    pytest.importorskip("rerun")
    from gait_planner.viz.rerun_view import save_rrd

    folder = tmp_path_factory.mktemp("ground_views")
    return {g: save_rrd(make_result(ground=g), folder / f"{i}.rrd")
            for i, g in enumerate((Ground(), RAMP, UP))}


def test_the_level_grid_is_as_before(views):
    h, step = 1.5, 0.25
    xs = np.arange(-h, h + step - 1e-9, step)
    ys = np.arange(-h, h + 1e-9, step)
    before = [[[x, -h, 0.0], [x, h, 0.0]] for x in xs] + [[[-h, y, 0.0], [xs[-1], y, 0.0]]
                                                          for y in ys]
    strips = _static(views[Ground()], "/world/ground", "LineStrips3D:strips")
    np.testing.assert_array_equal(np.array(strips, dtype=np.float32),
                                  np.array(before, dtype=np.float32))
    assert _static(views[Ground()], "/world/ground/treads", "Boxes3D:centers") is None


def test_the_grid_lies_on_the_ramp(views):
    strips = _static(views[RAMP], "/world/ground", "LineStrips3D:strips")
    points = np.array([p for strip in strips for p in strip])
    np.testing.assert_allclose(points[:, 2], RAMP.height(points[:, 0]), atol=1e-6)
    assert points[:, 2].max() > 0.25  # tilted: 1.5 m ahead is 0.26 m up


def test_the_grid_and_the_treads_follow_the_stairs(views):
    strips = _static(views[UP], "/world/ground", "LineStrips3D:strips")
    for strip in strips:
        strip = np.array(strip)
        for a, b in zip(strip, strip[1:]):  # each segment on a tread or up a riser
            if a[0] == b[0] and a[1] == b[1]:  # a riser: from the tread behind to the one ahead
                j = (float(a[0]) - UP.riser) / UP.tread  # edge j: treads j and j + 1
                assert j == pytest.approx(round(j), abs=1e-6)
                assert sorted([a[2], b[2]]) == pytest.approx(
                    [UP.tread_height(round(j)), UP.tread_height(round(j) + 1)], abs=1e-6)
            else:
                middle = 0.5 * (a[0] + b[0])
                assert a[2] == b[2] == pytest.approx(UP.height(middle), abs=1e-6)
    centres = np.array(_static(views[UP], "/world/ground/treads", "Boxes3D:centers"))
    halves = np.array(_static(views[UP], "/world/ground/treads", "Boxes3D:half_sizes"))
    np.testing.assert_allclose(centres[:, 2] + halves[:, 2], UP.height(centres[:, 0]),
                               atol=1e-6)


# ------------------------------------------------------------------ the MuJoCo walk


@pytest.fixture(scope="module")
def recordings(make_result, tmp_path_factory):
    """ground -> the synthetic walker3d result on it, recorded and read back."""
    folder = tmp_path_factory.mktemp("ground_recordings")
    out = {}
    for i, g in enumerate((LEVEL, RAMP, UP)):
        result = make_result(ground=g, settings={**make_result().settings, **g.metadata()})
        out[g] = (read_plan_mcap(write_plan_mcap(result, folder / f"{i}.mcap")), result.scene)
    return out


def _world_geoms(recordings, ground):
    pytest.importorskip("mujoco")
    from gait_planner.walk.mujoco_model import build_model

    rec, scene = recordings[ground]
    model = build_model(rec, scene, 0.05, 0.005, 1e-3, 0.005, 0.0).model
    return model, [i for i in range(model.ngeom) if model.geom_bodyid[i] == 0]


def test_mujoco_stands_a_level_plan_on_the_plane_z_0(recordings):
    model, geoms = _world_geoms(recordings, LEVEL)
    (g,) = geoms
    assert model.geom(g).name == "ground" and model.geom_type[g] == 0  # mjGEOM_PLANE
    np.testing.assert_array_equal(model.geom_quat[g], [1.0, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(model.geom_pos[g], 0.0)


def test_mujoco_tilts_the_plane_of_a_ramp(recordings):
    import mujoco

    model, (g,) = _world_geoms(recordings, RAMP)
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, model.geom_quat[g])
    np.testing.assert_allclose(R.reshape(3, 3)[:, 2], RAMP.normal, atol=1e-12)
    np.testing.assert_array_equal(model.geom_pos[g], 0.0)


def test_mujoco_builds_the_stairs_from_their_treads(recordings):
    from gait_planner.walk.mujoco_model import STAIR_TREADS, STAIRS_BEHIND

    model, geoms = _world_geoms(recordings, UP)
    assert all(model.geom_type[g] == 6 for g in geoms)  # mjGEOM_BOX
    pos, size = model.geom_pos[geoms], model.geom_size[geoms]  # size: half extents
    np.testing.assert_allclose(pos[:, 2] + size[:, 2], UP.height(pos[:, 0]), atol=1e-12)
    assert (pos[:, 0] - size[:, 0]).min() <= -STAIRS_BEHIND
    assert (pos[:, 0] + size[:, 0]).max() >= UP.riser + STAIR_TREADS * UP.tread - 1e-9
