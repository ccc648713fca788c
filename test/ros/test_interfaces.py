"""gait_planner_msgs: the generated types follow the interface contract (docs/design.md section 7)
and survive CDR serialisation with non-trivial values."""

from __future__ import annotations

import math

import pytest
from builtin_interfaces.msg import Duration, Time
from geometry_msgs.msg import Point, Vector3
from hypothesis import given, settings
from hypothesis import strategies as st
from rclpy.serialization import deserialize_message, serialize_message
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from gait_planner_msgs.action import PlanGait as PlanGaitAction
from gait_planner_msgs.msg import ContactForces, MultibodyState
from gait_planner_msgs.srv import PlanGait

pytestmark = pytest.mark.timeout(120)

CONTACTS = ["foot_r_heel", "foot_r_forefoot", "foot_l_heel", "foot_l_forefoot"]
BODIES = ["torso", "thigh_r", "calf_r", "foot_r", "thigh_l", "calf_l", "foot_l"]

# Field names and types as rosidl reports them: the contract others build on.
EXPECTED_FIELDS = {
    PlanGait.Request: {
        "scene": "string",
        "step_length": "double",
        "cost": "string",
        "friction_coefficient": "double",
        "intervals_per_phase": "int32",
        "max_solve_time": "double",
        "output_name": "string",
        "cold_start": "boolean",
        "steps": "int32",
        "posture": "string",
        "speed": "double",
        "slope": "double",
        "step_height": "double",
        "gait": "string",
        # a transition from a given or measured state onto the gait (issue #62)
        "start": "string",
        "state": "sensor_msgs/JointState",
        "root_pose": "geometry_msgs/Pose",
        "root_twist": "geometry_msgs/Twist",
        "transition_half_cycles": "int32",
        "stop": "boolean",  # end standing at rest
    },
    PlanGait.Response: {
        "success": "boolean",
        "message": "string",
        "solver_status": "string",
        "cost": "double",
        "step_length": "double",
        "duration": "double",
        "phase_scaling": "sequence<double>",
        "solve_time": "double",
        "iterations": "int32",
        "max_constraint_violation": "double",
        "max_dynamics_residual": "double",
        "max_friction_violation": "double",
        "trajectory": "trajectory_msgs/JointTrajectory",
        "mcap_path": "string",
        "continuous_torque_error": "double",
        "continuous_torque_error_at_switches": "double",
        "continuous_base_force": "double",
        "continuous_dynamics": "string",
        "walk_steps": "int32",
        "walk_half_cycles": "int32",
        "walk_feedback_share": "double",
        "walk_stopped": "string",
        "walk_touches": "int32",
        "walk_first_touch": "string",
    },
    ContactForces: {
        "header": "std_msgs/Header",
        "node": "uint32",
        "time": "double",
        "contact_names": "sequence<string>",
        "points": "sequence<geometry_msgs/Point>",
        "forces": "sequence<geometry_msgs/Vector3>",
        "wrench_bodies": "sequence<string>",
        "wrench_points": "sequence<geometry_msgs/Point>",
        "wrenches": "sequence<geometry_msgs/Wrench>",
        "centers_of_pressure": "sequence<geometry_msgs/Point>",
    },
    MultibodyState: {
        "header": "std_msgs/Header",
        "node": "uint32",
        "time": "double",
        "phase": "string",
        "active_contacts": "sequence<string>",
        "body_names": "sequence<string>",
        "q": "sequence<double>",
        "generalized_force": "sequence<double>",
        "kinetic_energy": "double",
        "potential_energy": "double",
        "held_joint_names": "sequence<string>",  # a drafted robot's locked joints (#61)
        "held_joint_impulses": "sequence<double>",  # N m s at an impact node
    },
}

# The action's goal and result are the service's request and response; its feedback:
EXPECTED_FIELDS[PlanGaitAction.Goal] = EXPECTED_FIELDS[PlanGait.Request]
EXPECTED_FIELDS[PlanGaitAction.Result] = EXPECTED_FIELDS[PlanGait.Response]
EXPECTED_FIELDS[PlanGaitAction.Feedback] = {
    "phase": "string", "iteration": "int32", "cost": "double",
    "constraint_violation": "double", "elapsed": "double"}


def roundtrip(message):
    data = serialize_message(message)
    assert isinstance(data, bytes) and len(data) > 0
    return deserialize_message(data, type(message))


def header(seconds: float) -> Header:
    whole = math.floor(seconds)
    return Header(
        stamp=Time(sec=whole, nanosec=round((seconds - whole) * 1e9)), frame_id="world"
    )


def sample_trajectory(nodes: int = 4) -> JointTrajectory:
    joints = ["hip_r_x", "hip_r_y", "hip_r_z", "knee_r", "ankle_r_x", "ankle_r_y", "ankle_r_z"]
    points = []
    for n in range(nodes):
        t = 0.05 * n
        points.append(
            JointTrajectoryPoint(
                positions=[0.1 * n + 0.01 * j for j in range(len(joints))],
                velocities=[-0.3 * n + j for j in range(len(joints))],
                effort=[12.5 * (j - 3) - n for j in range(len(joints))],
                time_from_start=Duration(sec=0, nanosec=round(t * 1e9)),
            )
        )
    return JointTrajectory(header=header(1700000000.25), joint_names=joints, points=points)


def sample_contact_forces() -> ContactForces:
    return ContactForces(
        header=header(1700000000.5),
        node=17,
        time=0.3125,
        contact_names=["foot_r_forefoot", "foot_l_heel"],
        points=[Point(x=0.61, y=-0.0936, z=0.0), Point(x=0.9, y=0.0936, z=-1e-12)],
        forces=[Vector3(x=-12.5, y=3.25, z=401.0), Vector3(x=20.0, y=-1.5e-3, z=87.75)],
    )


def sample_state() -> MultibodyState:
    q = [0.001 * i - 0.3 for i in range(12 * len(BODIES))]
    force = [(-1.0) ** i * 0.5 * i for i in range(12 * len(BODIES))]
    return MultibodyState(
        header=header(1700000001.0),
        node=3,
        time=0.0625,
        phase="single_support_right_full",
        active_contacts=["foot_r_heel", "foot_r_forefoot"],
        body_names=BODIES,
        q=q,
        generalized_force=force,
        kinetic_energy=41.2256,
        potential_energy=-1.5e-3,
    )


@pytest.mark.parametrize("message_type", list(EXPECTED_FIELDS), ids=lambda t: t.__name__)
def test_fields_follow_the_contract(message_type):
    assert message_type.get_fields_and_field_types() == EXPECTED_FIELDS[message_type]


def test_plan_gait_request_roundtrips():
    request = PlanGait.Request(
        scene="walker3d",
        step_length=0.6338,
        cost="kinetic_energy",
        friction_coefficient=0.8,
        intervals_per_phase=8,
        max_solve_time=120.5,
        output_name="walker3d_step0.6338",
        cold_start=True,
    )
    back = roundtrip(request)
    assert back == request
    assert back.step_length == 0.6338 and back.cold_start is True


def test_a_request_with_a_start_state_roundtrips():
    from geometry_msgs.msg import Pose, Twist
    from sensor_msgs.msg import JointState

    state = JointState(header=header(1700000002.5), name=["hip_r", "knee_r"],
                       position=[0.25, -1e-9], velocity=[-3.5, 0.0])
    pose, twist = Pose(), Twist()
    pose.position.z, pose.orientation.y, pose.orientation.w = 1.02, 0.1, 0.995
    twist.linear.x, twist.angular.y = 1.2, -0.4
    request = PlanGait.Request(scene="walker2d", start="state", state=state, root_pose=pose,
                               root_twist=twist, transition_half_cycles=3, stop=True)
    back = roundtrip(request)
    assert back == request and list(back.state.name) == ["hip_r", "knee_r"]
    assert back.state.header.stamp == state.header.stamp and back.root_twist.linear.x == 1.2


def test_plan_gait_response_roundtrips():
    response = PlanGait.Response(
        success=True,
        message="converged",
        solver_status="Solve_Succeeded",
        cost=41.2256,
        step_length=0.6338,
        duration=0.5988,
        phase_scaling=[1.5, 1.5, 1.4889, 1.4724],
        solve_time=12.75,
        iterations=231,
        max_constraint_violation=3.2e-12,
        max_dynamics_residual=1.1e-9,
        max_friction_violation=0.0,
        trajectory=sample_trajectory(),
        mcap_path="/tmp/runs/walker3d.mcap",
    )
    back = roundtrip(response)
    assert back == response
    assert list(back.phase_scaling) == [1.5, 1.5, 1.4889, 1.4724]
    assert len(back.trajectory.points) == 4
    assert list(back.trajectory.points[2].effort) == list(response.trajectory.points[2].effort)


def test_contact_forces_roundtrip():
    message = sample_contact_forces()
    back = roundtrip(message)
    assert back == message
    assert back.forces[0].z == 401.0 and back.points[1].z == -1e-12


def test_multibody_state_roundtrips():
    message = sample_state()
    back = roundtrip(message)
    assert back == message
    assert len(back.q) == 12 * len(back.body_names)


finite = st.floats(allow_nan=False, allow_infinity=True, width=64)  # NaN != NaN
# ROS strings are C strings: a NUL character ends them (found by this test), so none here.
ros_text = st.text(st.characters(codec="utf-8", exclude_characters="\x00"), max_size=20)


@settings(max_examples=50, deadline=None)
@given(
    node=st.integers(0, 2**32 - 1),
    time=finite,
    phase=ros_text,
    contacts=st.lists(st.sampled_from(CONTACTS), unique=True),
    bodies=st.integers(0, 7),
    data=st.data(),
)
def test_multibody_state_roundtrips_any_values(node, time, phase, contacts, bodies, data):
    q = data.draw(st.lists(finite, min_size=12 * bodies, max_size=12 * bodies))
    force = data.draw(st.lists(finite, min_size=12 * bodies, max_size=12 * bodies))
    message = MultibodyState(
        node=node,
        time=time,
        phase=phase,
        active_contacts=contacts,
        body_names=BODIES[:bodies],
        q=q,
        generalized_force=force,
        kinetic_energy=data.draw(finite),
        potential_energy=data.draw(finite),
    )
    assert roundtrip(message) == message


def test_action_feedback_survives_serialisation():
    feedback = PlanGaitAction.Feedback(phase="cold stage 2", iteration=57, cost=21.2283,
                                       constraint_violation=7.22e-07, elapsed=12.77)
    assert roundtrip(feedback) == feedback
