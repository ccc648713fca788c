"""MultibodyState and ContactForces travel from a publisher node to a subscriber node over
real rclpy and DDS, on the contract's topic names, in order and intact."""

from __future__ import annotations

import pytest
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Vector3
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Header

from gait_planner_msgs.msg import ContactForces, MultibodyState

pytestmark = pytest.mark.timeout(90)

NODES = 5  # time nodes of the fake plan
WAIT = 15.0  # s
BODIES = ["torso", "thigh_r", "calf_r", "foot_r", "thigh_l", "calf_l", "foot_l"]
# The latched profile a plan is published with: late subscribers still get the whole plan.
QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=100,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)


def stamp(n: int) -> Header:
    return Header(stamp=Time(sec=1700000000, nanosec=n * 12_500_000), frame_id="world")


def state(n: int) -> MultibodyState:
    return MultibodyState(
        header=stamp(n),
        node=n,
        time=0.0125 * n,
        phase="double_support" if n % 2 else "single_support",
        active_contacts=["foot_r_forefoot", "foot_l_heel"][: 1 + n % 2],
        body_names=BODIES,
        q=[0.01 * n + 0.001 * i for i in range(12 * len(BODIES))],
        generalized_force=[(-1.0) ** i * n * 0.1 for i in range(12 * len(BODIES))],
        kinetic_energy=60.0 + n,
        potential_energy=900.0 - n,
    )


def contact_forces(n: int) -> ContactForces:
    return ContactForces(
        header=stamp(n),
        node=n,
        time=0.0125 * n,
        contact_names=["foot_r_forefoot", "foot_l_heel"],
        points=[Point(x=0.6 + 0.01 * n, y=-0.0936, z=0.0), Point(x=1.2, y=0.0936, z=0.0)],
        forces=[Vector3(x=-5.0 * n, y=1.0, z=300.0 + n), Vector3(x=2.5, y=-0.5, z=100.0 - n)],
    )


@pytest.mark.parametrize(
    ("message_type", "topic", "make"),
    [
        (MultibodyState, "/gait_planner/state", state),
        (ContactForces, "/gait_planner/contact_forces", contact_forces),
    ],
    ids=["state", "contact_forces"],
)
def test_messages_reach_the_subscriber(
    make_node, executor, spin_until, message_type, topic, make
):
    publisher_node = make_node("gait_planner")
    publisher = publisher_node.create_publisher(message_type, topic, QOS)
    subscriber_node = make_node("gait_planner_test_listener")
    received = []
    subscriber_node.create_subscription(message_type, topic, received.append, QOS)
    executor.add_node(publisher_node)
    executor.add_node(subscriber_node)

    assert spin_until(
        lambda: publisher.get_subscription_count() > 0, WAIT
    ), f"no subscriber of {topic} discovered in {WAIT} s"
    sent = [make(n) for n in range(NODES)]
    for message in sent:
        publisher.publish(message)

    assert spin_until(lambda: len(received) >= NODES, WAIT), (
        f"{len(received)} of {NODES} messages on {topic} within {WAIT} s"
    )
    assert received == sent
