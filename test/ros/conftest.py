"""Fixtures for tests that talk over real ROS 2 (rclpy + Fast DDS), isolated and bounded.

Isolation: every test session claims a random ROS domain that no other session on this
machine holds (a lock file in the temp directory; the caller's ROS_DOMAIN_ID is ignored),
keeps discovery on this host and writes ROS logs to a temporary directory, so parallel runs
on one machine neither see each other nor a running gait_planner node. Every test gets its own
rclpy Context on that domain, shut down afterwards together with its nodes and executor.
Waits in these tests are bounded by `TIMEOUT` seconds.

`planner_node` serves a real `GaitPlannerNode` on its own multi-threaded executor (as
`gait-planner node` does), `node_process` runs `gait-planner node` as a process, and
`wait_for_feedback` waits for a matching action feedback message.
"""

from __future__ import annotations

import fcntl
import os
import random
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import IO, Any, Callable, Iterator

import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

TIMEOUT = 15.0  # s, longest wait for discovery or a message
REPO = Path(__file__).resolve().parents[2]
GAIT_PLANNER = Path(sys.executable).parent / "gait-planner"  # the venv's command


def _claim_domain_id() -> tuple[int, IO[str]]:
    """A random ROS domain id no other test session on this machine holds (a lock file)."""
    candidates = list(range(1, 101))  # 0 is everyone's default; ids <= 101 suit any host
    random.SystemRandom().shuffle(candidates)
    lock_dir = Path(tempfile.gettempdir())
    for domain_id in candidates:
        try:
            lock = open(lock_dir / f"gait_planner_ros_domain_{domain_id}.lock", "a")
        except OSError:  # e.g. another user's lock file
            continue
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            lock.close()
            continue
        return domain_id, lock
    raise RuntimeError("all ROS domain ids 1..100 are held by other test sessions")


@pytest.fixture(scope="session")
def ros_domain_id(tmp_path_factory: pytest.TempPathFactory) -> Iterator[int]:
    """This session's own ROS domain, with host-only discovery and private logs.

    Also exported as ROS_DOMAIN_ID, for processes a test starts."""
    domain_id, lock = _claim_domain_id()
    settings = {
        "ROS_DOMAIN_ID": str(domain_id),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "ROS_STATIC_PEERS": "",
        "ROS_LOG_DIR": str(tmp_path_factory.mktemp("ros_log")),
    }
    saved = {key: os.environ.get(key) for key in settings}
    os.environ.update(settings)
    try:
        yield domain_id
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
        lock.close()  # releases the domain


@pytest.fixture
def ros_context(ros_domain_id: int) -> Iterator[Context]:
    """An initialised rclpy Context on the session's domain; shut down after the test."""
    context = Context()
    rclpy.init(
        context=context,
        domain_id=ros_domain_id,
        signal_handler_options=SignalHandlerOptions.NO,  # leave Ctrl-C to pytest
    )
    try:
        yield context
    finally:
        context.try_shutdown()


@pytest.fixture
def make_node(ros_context: Context) -> Iterator[Callable[[str], Node]]:
    """Factory of nodes in the test's context; every node is destroyed after the test."""
    nodes: list[Node] = []

    def make(name: str) -> Node:
        node = Node(name, context=ros_context)
        nodes.append(node)
        return node

    try:
        yield make
    finally:
        for node in reversed(nodes):
            node.destroy_node()


@pytest.fixture
def executor(ros_context: Context) -> Iterator[SingleThreadedExecutor]:
    """A single-threaded executor of the test's context, shut down after the test."""
    executor = SingleThreadedExecutor(context=ros_context)
    try:
        yield executor
    finally:
        executor.shutdown(timeout_sec=TIMEOUT)


@pytest.fixture
def spin_until(executor: SingleThreadedExecutor) -> Callable[..., bool]:
    """``spin_until(done, timeout=TIMEOUT)``: spin the executor until ``done()`` holds or
    `timeout` seconds pass; returns ``done()``."""

    def spin(done: Callable[[], bool], timeout: float = TIMEOUT) -> bool:
        deadline = time.monotonic() + timeout
        while not done() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        return done()

    return spin


@pytest.fixture
def planner_node(ros_context: Context, tmp_path: Path) -> Iterator[Callable[..., Node]]:
    """``planner_node(**parameters)``: a `GaitPlannerNode` writing to `tmp_path` (its only
    allowed output folder; prepare_on_start and warm_start_store false and prepare_scenes none
    unless given, so a test's first plan is cold whatever earlier processes planned and no
    background preparation runs), served on a background thread by
    its own multi-threaded executor and `gait_planner.ros.node.serve`, as `gait-planner node`
    serves it, so a test's client spins apart from it. Closed, shut down and destroyed after
    the test."""
    from rclpy.executors import MultiThreadedExecutor
    from rclpy.parameter import Parameter

    from gait_planner.ros.node import EXECUTOR_THREADS, GaitPlannerNode, serve

    started: list[tuple[Node, MultiThreadedExecutor, threading.Thread]] = []
    stop = threading.Event()

    def start(**parameters) -> Node:
        values = {"output_dir": str(tmp_path), "allowed_output_dirs": [str(tmp_path)],
                  "prepare_on_start": False, "warm_start_store": False,
                  "prepare_scenes": [""], **parameters}
        node = GaitPlannerNode(context=ros_context, parameter_overrides=[
            Parameter(name, value=value) for name, value in values.items()])
        serving = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS, context=ros_context)
        serving.add_node(node)
        thread = threading.Thread(target=serve, args=(node, serving, stop.is_set), daemon=True)
        thread.start()
        started.append((node, serving, thread))
        return node

    try:
        yield start
    finally:
        stop.set()
        for node, serving, thread in started:
            node.close()
            thread.join(TIMEOUT)
            serving.shutdown(timeout_sec=TIMEOUT)
            node.destroy_node()


@pytest.fixture
def node_process(ros_domain_id: int, tmp_path: Path) -> Iterator[Callable[..., subprocess.Popen]]:
    """``node_process(*arguments)``: ``gait-planner node ARGUMENTS`` started in the
    repository (so config/gait_planner.yaml resolves), on the session's domain, its output
    in `tmp_path`/node.log; killed after the test if it still runs."""
    processes: list[subprocess.Popen] = []

    def start(*arguments: str) -> subprocess.Popen:
        log = open(tmp_path / "node.log", "ab")
        process = subprocess.Popen([str(GAIT_PLANNER), "node", *arguments], cwd=REPO,
                                   stdout=log, stderr=subprocess.STDOUT)
        log.close()
        processes.append(process)
        return process

    try:
        yield start
    finally:
        for process in processes:
            if process.poll() is None:
                process.kill()
                process.wait(TIMEOUT)


@pytest.fixture
def wait_for_feedback(spin_until: Callable[..., bool]) -> Callable[..., Any]:
    """``wait_for_feedback(feedback, done, timeout=60)``: spin until a message in the list
    `feedback` satisfies `done`, and return the first that does."""

    def wait(feedback: list, done: Callable[[Any], bool], timeout: float = 60.0) -> Any:
        assert spin_until(lambda: any(done(f) for f in feedback), timeout), (
            f"no such feedback within {timeout} s; got phases "
            f"{sorted({f.phase for f in feedback})}")
        return next(f for f in feedback if done(f))

    return wait
