"""A drafted robot walks on its own URDF (`gait_planner.walk.robot_urdf`,
`walk.director_frames`, `walk.mujoco_model.build_model(..., robot=...)`), checked without a
plan on G1, Bolt, Alexander and iCub from the example-robot-data wheel:

* the plan's frames sit where the scene puts them: at any root pose and leg angles, the
  ``plan_root`` site is the scene's root centre of mass and directors, each ``plan_<contact>``
  site the scene's contact point (1e-9 m), and the whole robot's centre of mass is the
  scene's (0.1 mm, and the mass to 1e-5: the draft makes left and right data symmetric);
* locked joints are welded at the draft's angles (G1's arms bent: the centre of mass
  still agrees), only the feet's own collision geometry is left, each of it mapped to the
  contact point it carries (G1: four 5 mm spheres per foot, heel pair and toe pair; Bolt:
  the meshes of its lower leg and of the foot fixed to it; Alexander: its visual foot
  meshes, its URDF having no collision geometry; iCub: its Collada foot meshes, given to
  MuJoCo as vertices), each foot's lowest vertex under and at the height of its contacts;
* a URDF that is not the scene's robot and a foot mesh that is not found are refused.
"""

from __future__ import annotations

import os
import types
from dataclasses import replace

import numpy as np
import pytest

from gait_planner.model.angles import angle_names, configuration
from gait_planner.model.loader import scene_from_text
from gait_planner.model.urdf_import import draft_scene

mujoco = pytest.importorskip("mujoco")

from gait_planner.walk.mujoco_model import build_model, plan_qpos  # noqa: E402
from gait_planner.walk.robot_urdf import RobotUrdf  # noqa: E402

G1 = "g1_description/urdf/g1_29dof_rev_1_0.urdf"
BOLT = "bolt_description/robots/bolt.urdf"
ICUB = "icub_description/robots/icub_reduced.urdf"
ALEXANDER = "alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf"
ARMS = {"left_shoulder_pitch_joint": -0.3, "right_shoulder_pitch_joint": -0.3,
        "left_elbow_joint": 0.8, "right_elbow_joint": 0.8}


def _walker(example_robots, path, locked=None):
    text = (example_robots / path).read_text()
    dirs = (str(example_robots.parents[1]),)
    draft = draft_scene(text, locked=locked, package_dirs=dirs)
    scene = scene_from_text(draft.yaml, f"{draft.name}.yaml")
    rec = types.SimpleNamespace(metadata={}, path=path, joint_names=angle_names(scene))
    wm = build_model(rec, scene, 0.03, 0.005, 5e-4, 0.005, 0.0,
                     RobotUrdf(text, dirs, draft.locked))
    return scene, wm, RobotUrdf(text, dirs, draft.locked)


@pytest.mark.parametrize("path, locked, tolerance", [
    (G1, None, 1e-9), (G1, ARMS, 1e-9), (BOLT, None, 1e-9), (ALEXANDER, None, 1e-9),
    (ICUB, None, 1e-4)])  # iCub: the draft writes its right joints' micrometres mirrored
def test_the_plans_frames_sit_where_the_scene_puts_them(example_robots, path, locked,
                                                         tolerance):
    scene, wm, _ = _walker(example_robots, path, locked)
    model, data = wm.model, mujoco.MjData(wm.model)
    rng = np.random.default_rng(7)
    names = angle_names(scene)
    for _ in range(3):
        angles = rng.uniform(-0.4, 0.4, len(names))
        pose = replace(scene.initial_pose, root_position=tuple(rng.uniform(-1, 1, 3)),
                       root_angles=tuple(rng.uniform(-0.6, 0.6, 3)),
                       joint_angles={n: (a,) for n, a in zip(names, angles)})
        q = configuration(scene, pose).reshape(-1, 12)
        i = scene.body_index(scene.root.body)
        data.qpos[:] = plan_qpos(wm, i, q.reshape(-1), angles)
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        assert np.allclose(data.site_xpos[wm.root_site], q[i, :3], atol=1e-9)
        assert np.allclose(data.site_xmat[wm.root_site].reshape(3, 3), q[i, 3:].reshape(3, 3).T,
                           atol=1e-9)
        for c, site in zip(scene.contacts, wm.contact_sites):
            b = scene.body_index(c.body)
            point = q[b, :3] + q[b, 3:].reshape(3, 3).T @ scene.body(c.body).points[c.point]
            assert np.allclose(data.site_xpos[site], point, atol=tolerance), c.name
        masses = np.array([b.mass for b in scene.bodies])
        com = masses @ q[:, :3] / masses.sum()
        assert np.allclose(data.subtree_com[model.body(wm.root).id], com, atol=1e-4)
        # the draft writes left and right data symmetric (Bolt: 1.5e-6 kg moved)
        assert float(model.body_subtreemass[model.body(wm.root).id]) == pytest.approx(
            masses.sum(), rel=1e-5)


def test_only_the_feet_collide_each_geometry_with_its_contact(example_robots):
    scene, wm, _ = _walker(example_robots, G1)
    model = wm.model
    feet = [g for g in range(model.ngeom) if model.geom_contype[g]]
    assert len(feet) == 8
    assert all(model.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE
               and model.geom_size[g, 0] == pytest.approx(0.005) for g in feet)
    contacts = [scene.contacts[wm.geom_contact[g]] for g in feet]
    for g, c in zip(feet, contacts):
        assert model.body(model.geom_bodyid[g]).name == c.body
        heel = model.geom_pos[g, 0] < 0  # G1's heel spheres at x = -0.05 m, toes at 0.12 m
        assert c.point == ("heel" if heel else "forefoot")
    bolt_scene, bolt, _ = _walker(example_robots, BOLT)
    meshes = [g for g in range(bolt.model.ngeom) if bolt.model.geom_contype[g]]
    # per leg the lower leg's mesh and that of the foot fixed below it: one rigid body
    assert [bolt.model.geom_type[g] for g in meshes] == [mujoco.mjtGeom.mjGEOM_MESH] * 4
    for g in meshes:
        contact = bolt_scene.contacts[bolt.geom_contact[g]]
        assert bolt.model.body_weldid[bolt.model.geom_bodyid[g]] == \
            bolt.model.body(contact.body).id


@pytest.mark.parametrize("path, from_vertices", [(ICUB, 2), (ALEXANDER, 0)])
def test_feet_read_from_visual_or_collada_meshes_touch_where_their_contacts_are(
        example_robots, path, from_vertices):
    """Alexander's feet have only visual meshes, iCub's Collada ones (which MuJoCo does not
    read: given as vertices): in MuJoCo at the draft's initial pose each foot's lowest
    vertex is at its contacts' height and under them."""
    scene, wm, _ = _walker(example_robots, path)
    model, data = wm.model, mujoco.MjData(wm.model)
    feet = [g for g in range(model.ngeom) if model.geom_contype[g]]
    assert len(feet) == 2 and all(model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH
                                  for g in feet)
    assert sum(model.mesh(model.geom_dataid[g]).name.startswith("foot_mesh_")
               for g in feet) == from_vertices
    q = configuration(scene).reshape(-1, 12)
    i = scene.body_index(scene.root.body)
    data.qpos[:] = plan_qpos(wm, i, q.reshape(-1), np.zeros(len(angle_names(scene))))
    mujoco.mj_kinematics(model, data)
    for g in feet:
        mesh = model.geom_dataid[g]
        start = model.mesh_vertadr[mesh]
        local = model.mesh_vert[start:start + model.mesh_vertnum[mesh]]
        world = local @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]
        sites = [data.site_xpos[s] for c, s in zip(scene.contacts, wm.contact_sites)
                 if scene.contacts[wm.geom_contact[g]].body == c.body]
        assert len(sites) == 2  # heel and forefoot
        for site in sites:
            assert abs(site[2] - world[:, 2].min()) < 1e-3  # the sole band of the draft
            assert world[:, 0].min() < site[0] < world[:, 0].max()
            assert world[:, 1].min() < site[1] < world[:, 1].max()


def test_links_without_inertia_take_the_drafts(example_robots):
    """iCub's URDF gives its right leg links a mass but no inertia: MuJoCo gets the draft's
    body (the left twin's mirror image, same principal moments); its ankle_2, whose fixed
    foot carries the inertia, stays a point mass."""
    scene, wm, _ = _walker(example_robots, ICUB)
    model = wm.model
    for right, left in (("r_upper_leg", "l_upper_leg"), ("r_hip_1", "l_hip_1")):
        assert np.allclose(np.sort(model.body(right).inertia), np.sort(model.body(left).inertia),
                           rtol=1e-6, atol=0)  # MuJoCo's own eigen solver
        assert np.allclose(np.sort(model.body(right).inertia), np.sort(scene.body(right).inertia),
                           rtol=1e-6, atol=0)  # MuJoCo's own eigen solver
    assert model.body("r_ankle_2").inertia.max() < 1e-8


def test_another_robot_and_a_missing_mesh_are_refused(example_robots):
    scene, _, g1 = _walker(example_robots, G1)
    rec = types.SimpleNamespace(metadata={}, path="g1", joint_names=angle_names(scene))
    shifted = g1.text.replace('<origin xyz="0 0 -0.017558" rpy="0 0 0"/>',
                              '<origin xyz="0 0 -0.027558" rpy="0 0 0"/>', 1)
    with pytest.raises(ValueError, match="not scene .*'s: at the zero pose a joint anchor"):
        build_model(rec, scene, 0.03, 0.005, 5e-4, 0.005, 0.0, replace(g1, text=shifted))
    bolt_scene, _, bolt = _walker(example_robots, BOLT)
    rec = types.SimpleNamespace(metadata={}, path="bolt", joint_names=angle_names(bolt_scene))
    with pytest.raises(ValueError, match="collision mesh .*lower_leg.*stl.* of foot link "
                       ".FL_LOWER_LEG. is not found"):
        build_model(rec, bolt_scene, 0.03, 0.005, 5e-4, 0.005, 0.0,
                    replace(bolt, package_dirs=()))


def test_a_recording_keeps_where_its_meshes_resolved(example_robots, make_result, tmp_path):
    """A scene that names its URDF relative to itself: the recording's copy of that scene has
    no folder, so the walk finds Talos's package:// foot meshes through the folders the
    plan's metadata names (`robot_package_dirs`), and without them finds none."""
    from gait_planner.io.mcap_writer import plan_metadata
    from gait_planner.walk.walk_plan import recorded_robot

    urdf = example_robots / "talos_data/robots/talos_reduced.urdf"
    share, text = str(example_robots.parents[1]), urdf.read_text()
    # as `gait-planner scene from-urdf` without --package-dir: the meshes resolve in the
    # URDF's parents, and the scene names no folder
    draft = draft_scene(text, package_dirs=[share], urdf_file=os.path.relpath(urdf, tmp_path),
                        mirror_tolerance=0.06)
    planned = scene_from_text(draft.yaml, "talos.yaml", tmp_path)  # as the planner loads it
    meta = plan_metadata(make_result(scene=planned))
    assert share in meta["robot_package_dirs"].split(os.pathsep)
    recorded = scene_from_text(draft.yaml, "talos.yaml")  # the recording's attachment
    assert recorded.robot.search_dirs() == ()
    rec = types.SimpleNamespace(urdf=text, metadata=meta)
    assert share in recorded_robot(rec, recorded).package_dirs
