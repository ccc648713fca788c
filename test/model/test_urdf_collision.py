"""Spheres fitted to the lower legs' collision geometry (`gait_planner.model.urdf_collision`),
the leg clearance rows' distances (`gait_planner.ocp.legs`) and the verifier's measure of
the legs' distance (`gait_planner.verify.legs`), on G1's, Talos's and iCub's URDFs:

* the fit contains every piece it is given (any triangles, spheres and capsules), whole;
* the spheres a draft writes contain the URDF's collision geometry at the zero pose
  (its vertices and random points on its triangles, placed by Pinocchio);
* the rows' sphere distances are coal's distances between the same spheres, and never
  more than coal's distance between the URDF's own collision geometry (the spheres
  contain it), at random poses of the legs within the draft's ranges;
* iCub's Collada meshes (<up_axis>Y_UP) are placed turned to z up, as its authors' viewers
  place them, in the draft's fit and in the verifier: its shanks stand along its legs,
  apart, not across its hips (before, coal found its standing legs touching and the
  spheres of radius 21 cm overlapped by 29 cm, so no leg row could hold).
"""

from __future__ import annotations

import math

import coal
import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.model.angles import configuration
from gait_planner.model.loader import scene_from_text
from gait_planner.model.multibody import Multibody
from gait_planner.model.urdf_contacts import turn_y_up
from gait_planner.model.scene import InitialPose
from gait_planner.model.urdf_collision import fit_spheres
from gait_planner.model.urdf_import import draft_scene
from gait_planner.ocp.legs import leg_bodies, leg_sphere_distances
from gait_planner.verify.continuous import effort_names
from gait_planner.verify.legs import leg_clearance
from gait_planner.verify.mechanics import parse_scene
from gait_planner.verify.robot import urdf_configurations

ROBOTS = {"g1": ("g1_description/urdf/g1_29dof_rev_1_0.urdf", {}),
          "talos": ("talos_data/robots/talos_reduced.urdf", {"mirror_tolerance": 0.06}),
          "icub": ("icub_description/robots/icub_reduced.urdf", {})}


def _inside(points: np.ndarray, spheres: np.ndarray) -> np.ndarray:
    """Whether each point (n, 3) lies in one of the spheres (s, 4) (1e-12 m round-off)."""
    gap = np.linalg.norm(points[:, None] - spheres[None, :, :3], axis=2) - spheres[None, :, 3]
    return gap.min(axis=1) <= 1e-12


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_fitted_spheres_contain_every_piece_whole(seed):
    rng = np.random.default_rng(seed)
    size = rng.uniform(0.02, 0.4, 3)
    pieces = [(rng.uniform(-1, 1, (3, 3)) * size, 0.0) for _ in range(rng.integers(1, 60))]
    pieces += [(rng.uniform(-1, 1, (rng.integers(1, 3), 3)) * size, rng.uniform(0, 0.05))
               for _ in range(rng.integers(0, 5))]  # spheres and capsules
    lateral = rng.normal(size=3)
    spheres = fit_spheres(pieces, lateral, count=int(rng.integers(1, 16)))
    samples = []
    for points, rho in pieces:
        w = rng.dirichlet(np.ones(len(points)), 50)
        out = rng.normal(size=(50, 3))
        out *= rho * rng.uniform(0, 1, (50, 1)) ** (1 / 3) / np.linalg.norm(out, axis=1)[:, None]
        samples.append(np.vstack([w @ points + out, points]))
    assert _inside(np.vstack(samples), spheres).all()


@pytest.fixture(scope="module", params=sorted(ROBOTS))
def drafted(request, example_robots):
    """(name, URDF text, Pinocchio model and collision geometry, Scene, SceneData, the
    metadata that finds the meshes)."""
    relative, options = ROBOTS[request.param]
    path = example_robots / relative
    urdf = path.read_text()
    draft = draft_scene(urdf, package_dirs=[str(example_robots.parents[1])],
                        urdf_file=str(path), **options)
    scene = scene_from_text(draft.yaml, f"{request.param}.yaml", path.parent)
    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    geometry = turn_y_up(pin.buildGeomFromUrdfString(  # iCub's Collada meshes: Y_UP
        model, urdf, pin.GeometryType.COLLISION, package_dirs=[str(example_robots.parents[1])]))
    return (request.param, urdf, model, geometry, scene, parse_scene(draft.yaml),
            {"robot_package_dirs": str(example_robots.parents[1])})


def _pose(scene, data_scene, rng=None):
    """(q (k,), URDF angles (na,) in `effort_names` order): the zero pose, or with rng
    every leg joint at a random angle of its range."""
    limits = scene.gait.options["joint_limits"]
    angles = {}
    for j in scene.joints:
        angles[j.name] = tuple(
            0.0 if rng is None else math.radians(rng.uniform(*limits[a])) if a in limits
            else 0.0 for a in (j.angle_names or (j.name,)))
    pose = InitialPose(scene.initial_pose.root_position, scene.initial_pose.root_angles, angles)
    by_name = {a: v for j in scene.joints for a, v in zip(j.angle_names or (j.name,),
                                                          angles[j.name])}
    return (configuration(scene, pose),
            np.array([by_name[n] for n in effort_names(data_scene)]))


def test_drafted_spheres_contain_the_urdfs_collision_geometry(drafted):
    name, urdf, model, geometry, scene, data_scene, _ = drafted
    q, angles = _pose(scene, data_scene)
    config = urdf_configurations(data_scene, model, q[None], angles[None])[0]
    data, gdata = model.createData(), pin.GeometryData(geometry)
    pin.updateGeometryPlacements(model, data, geometry, gdata, config)
    rng = np.random.default_rng(7)
    checked = 0
    for body in (b for leg in leg_bodies(scene) for b in leg):
        i = scene.body_index(body)
        phi, D = q[12 * i:12 * i + 3], q[12 * i + 3:12 * i + 12].reshape(3, 3).T
        spheres = np.array([np.r_[phi + D @ s[:3], s[3]] for s in scene.body(body).collision])
        joint = model.frames[model.getFrameId(body)].parentJoint
        for k, obj in enumerate(geometry.geometryObjects):
            if obj.parentJoint != joint:
                continue
            M, geom = gdata.oMg[k], obj.geometry
            if hasattr(geom, "tri_indices"):
                v = np.asarray(geom.vertices()) @ M.rotation.T + M.translation
                tri = np.array([[t[a] for a in range(3)] for t in
                                (geom.tri_indices(m) for m in range(geom.num_tris))])
                w = rng.dirichlet(np.ones(3), len(tri))
                points = np.vstack([v, np.einsum("ta,tax->tx", w, v[tri])])
            else:  # G1's soles: spheres
                u = rng.normal(size=(200, 3))
                points = M.translation + geom.radius * u / np.linalg.norm(u, axis=1)[:, None]
            assert _inside(points, spheres).all(), f"{name}: {obj.name} sticks out"
            checked += len(points)
    assert checked > 900  # iCub: 996 points on its simple meshes


def test_sphere_distances_are_coals_and_bound_the_geometrys(drafted):
    name, urdf, model, geometry, scene, data_scene, metadata = drafted
    mb = Multibody(scene)
    distances = leg_sphere_distances(mb)
    left, right = leg_bodies(scene)
    rng = np.random.default_rng(3)
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    margins = []
    for _ in range(12):
        q, angles = _pose(scene, data_scene, rng)
        ours = distances(q).full().ravel()
        # the rows' pairs: every left sphere against every right one, in scene order
        spheres = []
        for leg in (left, right):
            spheres.append([])
            for body in leg:
                i = scene.body_index(body)
                phi, D = q[12 * i:12 * i + 3], q[12 * i + 3:12 * i + 12].reshape(3, 3).T
                spheres[-1] += [(phi + D @ s[:3], s[3]) for s in scene.body(body).collision]
        theirs = [coal.distance(coal.Sphere(ra), coal.Transform3s(np.eye(3), ca),
                                coal.Sphere(rb), coal.Transform3s(np.eye(3), cb),
                                request, result)
                  for ca, ra in spheres[0] for cb, rb in spheres[1]]
        np.testing.assert_allclose(ours, theirs, atol=1e-9)
        true = leg_clearance(data_scene, q[None], metadata, urdf, angles[None])
        assert "coal" in true.source
        assert ours.min() <= true.smallest + 1e-9
        margins.append(true.smallest - ours.min())
    assert min(margins) >= 0


def test_icubs_y_up_shanks_stand_along_its_legs_apart(drafted):
    """Standing (the draft's pose, the URDF's zero), iCub's lower legs are 45 mm apart by
    coal on its turned meshes and the spheres 22 mm (G1's and Talos's: 165 and 28 mm,
    their spheres 122 and 5.5 mm); every sphere smaller than the shank's length."""
    name, urdf, model, geometry, scene, data_scene, metadata = drafted
    q, angles = _pose(scene, data_scene)
    true = leg_clearance(data_scene, q[None], metadata, urdf, angles[None])
    spheres = leg_sphere_distances(Multibody(scene))(q).full().ravel()
    assert "coal" in true.source
    expected = {"g1": (0.1654, 0.1218), "talos": (0.0276, 0.0055), "icub": (0.0451, 0.0221)}
    np.testing.assert_allclose((true.smallest, spheres.min()), expected[name], atol=2e-4)
    if name == "icub":
        assert true.pair == ("l_lower_leg", "r_lower_leg")
        assert max(s[3] for s in scene.body("l_lower_leg").collision) < 0.06


def test_the_drafts_leg_clearance_is_an_option_and_a_negative_one_is_refused(example_robots):
    from gait_planner.model.urdf_errors import UrdfError

    relative, options = ROBOTS["g1"]
    path = example_robots / relative
    dirs = [str(example_robots.parents[1])]
    draft = draft_scene(path.read_text(), package_dirs=dirs, leg_clearance=0.025)
    assert scene_from_text(draft.yaml, "g1.yaml").gait.options["leg_clearance"] == 0.025
    with pytest.raises(UrdfError, match="--leg-clearance takes a distance >= 0 m"):
        draft_scene(path.read_text(), package_dirs=dirs, leg_clearance=-0.01)
