"""Property-based robustness of a live `gait-planner node` (project issue #13, item 4).

Hypothesis draws PlanGait requests with hostile fields (NaN, +-inf, huge, negative, zero and
subnormal floats; ints over the whole int32 range; empty, unicode, 10k-character, path-like
and NUL-carrying strings; unknown scenes, costs and postures) mixed with mostly valid compass
requests, so that some are planned. They go to ONE node process started once for this module
(`gait-planner node ... -p default_scene:=compass -p prepare_on_start:=false
-p max_solve_time:=3.0`, output folder and only allowed folder a pytest temporary folder),
through four clients, each a thread with its own rclpy Context and node: service calls,
action goals (some canceled at a random moment) and bursts in which the other clients send
service calls and goals at once while a goal runs.

Asserted for every request:
* the node process is alive after every example;
* every answer arrives within its limit: 1 s (`GRACE`) + the time limit of the solve (the
  request's max_solve_time, or the node's 3.0 s when 0) + what the node does outside the
  solve, for which the limit does not stand (`gait_planner.strategies.plan_once`):
  building a problem not built before (`BUILD_ALLOWANCE`, once per problem), and recording
  the found plan (`RECORD_ALLOWANCE` + `RECORD_PER_STEP` per half cycle: the certificate,
  MCAP and .rrd of up to 100 joined half cycles), plus `FIRST_ALLOWANCE` for the first plan
  of the process (imports). For goals the feedback phases split the answer time, so the
  solve itself (end of "building" to "recording" or the result) is held to limit + 1 s;
* a busy answer, a goal rejection and a refused request arrive within `FAST` s; a request
  sent while another plan was running (an accepted goal whose result came later) is
  answered busy / rejected, not queued;
* every refusal (success False) has a non-empty message: exactly the `RequestError` the
  node's own checks give for the request as received (`predicted_refusal`), which names a
  request field, or "busy ...", or the solver's reason ("IPOPT: ..."), or "stopped on
  request" for a canceled goal; never "internal error";
* a goal's end agrees with its cancel's answer: canceled only if the cancel was accepted,
  recorded only if it was refused (recording had begun), a cancel answered within `FAST` s
  (`FAST` + `BUILD_ALLOWANCE` while a problem is built);
* every accepted plan's MCAP (the response's path) is inside the output folder, reads back
  with `read_plan_mcap` with as many points as the answered trajectory, and has a name no
  earlier plan of the session got (unless the request named the same file); the output
  folder holds only the recordings of accepted plans (no temporaries left);
* nothing is written outside the output folder: the repository tree, the pytest temporary
  root and /tmp are compared before and after (`test_fuzz_wrote_nothing_outside_the_output_
  folder`, after the node stopped). Other people edit the repository and use /tmp meanwhile,
  so what fails is what could be the node's: a new or changed file whose name is a
  recording's or temporary's (.mcap, .rrd, .tmp) or holds a name the node was sent, a new
  file at the repository's top level (the node's working folder), anything in runs/ or
  config/, any new entry in the pytest root but this module's folders. Other changes are
  listed in the summary. The derivative cache (~/.cache/gait_planner) is the node's by
  design and not checked.

Strings are cut at the first NUL on the way (ROS 2 strings are C strings): the node sees
"a\\0b" as "a", so the expected refusal is computed for the string as received.

Size: ``GAIT_PLANNER_FUZZ_EXAMPLES`` examples (default 40, seeded: `@seed`, so
`make test` runs the same subset, well under a minute); ``make fuzz`` runs 1000. The counts
(accepted, refused, busy, rejected, canceled ...) and the slowest answer against its limit
are printed at the end (``-s``) and written to `fuzz_summary.json` in the pytest temporary
folder.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import threading
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import pytest
import rclpy
from action_msgs.msg import GoalStatus
from hypothesis import HealthCheck, Phase, example, given, seed, settings
from hypothesis import strategies as st
from rclpy.action import ActionClient
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.ocp.solve import STOPPED, _key
from gait_planner.pipeline import output_stem
from gait_planner.request import MAX_STEPS, RequestError, plan_request
from gait_planner.ros.action_server import ACTION
from gait_planner.ros.node import BUSY, SERVICE
from gait_planner.problem import resolve
from gait_planner_msgs.action import PlanGait as PlanGaitAction
from gait_planner_msgs.srv import PlanGait

REPO = Path(__file__).resolve().parents[2]
GAIT_PLANNER = Path(sys.executable).parent / "gait-planner"  # the venv's command (conftest)

EXAMPLES = int(os.environ.get("GAIT_PLANNER_FUZZ_EXAMPLES", "40"))
pytestmark = [pytest.mark.fuzz, pytest.mark.timeout(120 + 6 * EXAMPLES)]

DEFAULT_SCENE = "compass"
NODE_MAX_SOLVE_TIME = 3.0  # s, the node's default limit (-p max_solve_time), for 0
MAX_PLAN_TIME = 3.0  # s, the largest limit a request that will be planned gets (strategy)
GRACE = 1.0  # s, on top of every limit (the "+ 1 s")
FAST = 1.0  # s, a busy answer, a goal rejection, a refusal (checks take microseconds)
# Allowances for what the time limit does not cover (strategies.plan_once: "building a problem the
# planner has not seen before comes on top"; recording comes after the solve). Measured on
# this 2-core machine under a load of 4-6 (other jobs): compass builds at most 0.17 s in
# `make fuzz` (compiled derivative elements from the cache); recording 0.3 s + about 0.05 s
# per half cycle (100 half cycles: 5.4 s); the first plan of the process also imports the
# recording modules (its recording: 0.6-0.7 s). Each allowance is several times the largest
# value seen, for the load of a shared machine. (In the 1000-example run no answer needed
# them: the slowest took 0.84 of its bare limit + 1 s.)
BUILD_ALLOWANCE = 3.0  # s, once per problem (scene, grid, cost, posture)
RECORD_ALLOWANCE = 1.5  # s, plus RECORD_PER_STEP per half cycle, for a found plan
RECORD_PER_STEP = 0.1  # s per half cycle
FIRST_ALLOWANCE = 3.0  # s, the first plan of the process
# A request sent this long before the running goal's result came may have reached the node
# after its plan thread ended (the node frees itself, then sends the result).
OVERLAP_MARGIN = 0.3  # s
WAIT_EXTRA = 30.0  # s a client waits beyond an answer's limit before calling it a hang
FIELDS = ("scene", "step_length", "cost", "friction_coefficient", "intervals_per_phase",
          "max_solve_time", "output_name", "steps", "posture", "speed", "slope",
          "step_height", "gait")
# Folders other people change while this test runs (not the node's doing), and caches.
SHARED = ("benchmarks", "benchmarks/collocation", "test/collocation")
SKIPPED_DIRS = {".git", ".venv", "__pycache__", ".pytest_cache", ".hypothesis", "build",
                "install", "log"}


# ------------------------------------------------------------------- what the node will do

def received(text: str) -> str:
    """A string as the node receives it (a ROS 2 string is a C string: cut at NUL)."""
    return text.split("\0", 1)[0]


def as_received(request):
    """A copy of `request` (Request or Goal) with its strings as the node receives them."""
    copy = type(request)()
    for name in request.get_fields_and_field_types():
        value = getattr(request, name)
        setattr(copy, name, received(value) if isinstance(value, str) else value)
    return copy


def node_request(request):
    """The node's PlanRequest of `request` as received (RequestError if it breaks the
    fields' rule, `gait_planner.request`)."""
    return plan_request(as_received(request), default_scene=DEFAULT_SCENE,
                        default_max_solve_time=NODE_MAX_SOLVE_TIME, compiled=True)


def predicted_refusal(request) -> str | None:
    """The node's RequestError message for `request` (its checks before planning, in the
    order `plan_and_record` makes them), or None if the node will plan it."""
    try:
        plan = node_request(request)
        scene = resolve(plan).scene
        output_stem(plan, scene.name)
    except RequestError as err:
        return str(err)
    return None


def problem_key(request):
    """The node's cache key of the problem a plannable request builds."""
    problem = resolve(node_request(request))
    return _key(problem.scene, problem.settings)


def solve_limit(request) -> float:
    return request.max_solve_time or NODE_MAX_SOLVE_TIME


def steps_of(request) -> int:
    return request.steps or 1


# ------------------------------------------------------------------------------ strategies

NAN, INF = float("nan"), float("inf")
WILD_FLOATS = st.one_of(
    st.sampled_from([NAN, -NAN, INF, -INF, 0.0, -0.0, 5e-324, -5e-324, 1e-300, 2.2e-308,
                     1e300, 1.7976931348623157e308, -1.7976931348623157e308, -1.0, -1e9,
                     3600.0000001, 1e6, 2.0000001, 5.0000001, 0.0499999]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=-10, max_value=10),
)
INT32 = st.integers(min_value=-2**31, max_value=2**31 - 1)
WILD_INTS = st.one_of(
    st.sampled_from([-2**31, -2**31 + 1, -1, 0, 1, 2, 31, 32, 33, 100, 101, 2**31 - 1]),
    INT32)
PATHS = ["../x", "/etc/passwd", "a/b", "..", ".", "./", "/", "~", "~/x", "$HOME", "x\0y",
         "\0", "compass\0/../../etc/passwd", "..\\x", "C:\\x", "con", "-rf", "*", " ",
         "compass ", " compass", "COMPASS", "compass.yaml", "config/scenes/compass",
         "/tmp/gait_fuzz_escape", "../../tmp/gait_fuzz_escape", "x.mcap/..", "a" * 129,
         "é", "名前", "\n", "%s%n", "${x}"]
LONG = st.text(min_size=1, max_size=3).map(lambda s: (s * 10_000)[:10_000])
WILD_TEXT = st.one_of(st.just(""), st.sampled_from(PATHS), st.text(max_size=40), LONG)


def names(*valid: str) -> st.SearchStrategy[str]:
    """A field's valid values (and empty = the default) or anything hostile."""
    return st.one_of(st.sampled_from(("",) + valid), WILD_TEXT)


@st.composite
def wild_requests(draw) -> dict:
    """Every field from its hostile pool or its valid values: nearly always refused."""
    request = dict(
        scene=draw(names("compass", "walker2d", "walker3d", "unknown_scene")),
        step_length=draw(st.one_of(WILD_FLOATS, st.floats(0.05, 2.5))),
        cost=draw(names("kinetic_energy", "torque_squared", "energy")),
        friction_coefficient=draw(st.one_of(WILD_FLOATS, st.floats(0.01, 6.0))),
        intervals_per_phase=draw(st.one_of(WILD_INTS, st.integers(-3, 40))),
        max_solve_time=draw(st.one_of(WILD_FLOATS, st.floats(0.01, MAX_PLAN_TIME))),
        output_name=draw(names("fuzz_wild", "fuzz.wild", "fuzz_wild.mcap")),
        cold_start=draw(st.booleans()),
        steps=draw(st.one_of(WILD_INTS, st.integers(-3, 120))),
        posture=draw(names("paper", "human", "robot")),
        speed=draw(st.one_of(WILD_FLOATS, st.floats(0.0, 5.0))),
        slope=draw(st.one_of(WILD_FLOATS, st.floats(-60.0, 60.0))),
        step_height=draw(st.one_of(WILD_FLOATS, st.floats(-1.0, 1.0))),
        gait=draw(names("walk", "run", "hop")),
    )
    return request


@st.composite
def plannable_requests(draw) -> dict:
    """Mostly valid compass requests (defaults, small grids, small time limits): planned."""
    return dict(
        scene=draw(st.sampled_from(["compass", "", "compass", "compass\0ignored"])),
        # compass plans are found for step lengths up to about 0.45 m with mu >= 0.6 (and
        # the scene's defaults); a few infeasible and time-starved ones fail in the solver
        step_length=draw(st.one_of(st.just(0.0), st.floats(0.2, 0.45),
                                   st.floats(0.2, 0.45), st.floats(0.45, 1.2))),
        cost=draw(st.sampled_from(["", "kinetic_energy", "torque_squared"])),
        friction_coefficient=draw(st.one_of(st.just(0.0), st.floats(0.6, 2.0),
                                            st.floats(0.05, 0.6))),
        intervals_per_phase=draw(st.sampled_from([0, 0, 4, 6, 8, 12])),
        max_solve_time=draw(st.one_of(st.just(0.0),
                                      st.floats(0.5, MAX_PLAN_TIME),
                                      st.floats(0.5, MAX_PLAN_TIME),
                                      st.floats(0.5, MAX_PLAN_TIME),
                                      st.sampled_from([1e-9, 5e-324, 0.01, 0.05]))),
        output_name=draw(st.sampled_from(["", "", "fuzz_plan", "fuzz.plan.mcap",
                                          "fuzz_plan\0/../../escape"])),
        cold_start=draw(st.booleans()),
        steps=draw(st.sampled_from([0, 1, 1, 2, 4, 20])),
        posture=draw(st.sampled_from(["", "paper", "human"])),
        # a held speed and a ground other than level build problems of their own, whose
        # compiled elements `make setup` does not prepare (compass: 20-30 s of gcc each,
        # far beyond BUILD_ALLOWANCE), so a plannable request keeps free durations on level
        # ground (`cheap`) and the wild ones draw the others
        gait=draw(st.sampled_from(["", "", "walk", "run"])),
    )


def cheap(request: dict) -> dict:
    """Keep what will be planned cheap: a plannable walker request becomes a compass one
    with free durations on level ground (`plannable_requests`), and a plannable request's
    time limit is at most MAX_PLAN_TIME."""
    msg = PlanGait.Request(**request)
    if predicted_refusal(msg) is None:
        if received(msg.scene) not in ("", "compass"):
            request = {**request, "scene": "compass"}
        request = {**request, "speed": 0.0, "slope": 0.0, "step_height": 0.0}
        if request["max_solve_time"] > MAX_PLAN_TIME:
            request = {**request, "max_solve_time": MAX_PLAN_TIME}
    return request


REQUESTS = st.one_of(wild_requests(), plannable_requests(), plannable_requests(),
                     plannable_requests()).map(cheap)


QUIET = dict(scene="", step_length=0.0, cost="", friction_coefficient=0.0,
             intervals_per_phase=0, max_solve_time=1.0, output_name="", cold_start=False,
             steps=0, posture="", speed=0.0, slope=0.0, step_height=0.0,
             gait="")  # every field "the default"


@dataclass
class Scenario:
    """One example: a first request (service or goal, a goal perhaps canceled) and the
    requests other clients send at once while the goal runs."""

    request: dict
    via: str  # "service" or "action"
    cancel_after: float | None  # s after the goal's acceptance; None: no cancel
    others: list[tuple[str, dict]] = field(default_factory=list)  # (via, request)


@st.composite
def scenarios(draw) -> Scenario:
    via = draw(st.sampled_from(["service", "action"]))
    cancel_after = None
    others: list = []
    if via == "action":
        cancel_after = draw(st.one_of(st.none(), st.none(), st.floats(0.0, 1.0)))
        if draw(st.integers(0, 2)) == 0:
            others = draw(st.lists(st.tuples(st.sampled_from(["service", "action"]), REQUESTS),
                                   min_size=1, max_size=3))
            # the goal they meet: a plan, with a few half cycles to record (the node is busy
            # while it records too; a cancel is refused then)
            request = draw(plannable_requests().map(cheap))
            request["steps"] = draw(st.sampled_from([request["steps"], 4, 8]))
            return Scenario(request, via, cancel_after, others)
    return Scenario(draw(REQUESTS), via, cancel_after, others)


# --------------------------------------------------------------------------------- clients

@dataclass
class Answer:
    via: str
    request: Any
    sent: float
    done: float | None = None
    accepted: bool | None = None  # goals: accepted or rejected
    status: int | None = None  # goals: final status
    response: Any = None  # Response / Result
    feedback: list = field(default_factory=list)  # (monotonic time, phase)
    accepted_at: float | None = None
    cancel_sent: float | None = None
    cancel_phase: str | None = None  # the last phase heard when the cancel was sent
    cancel_accepted: bool | None = None  # the cancel's answer (None: none within FAST)

    @property
    def elapsed(self) -> float:
        return (self.done if self.done is not None else time.monotonic()) - self.sent

    @property
    def busy(self) -> bool:
        return self.accepted is False or (
            self.response is not None and self.response.message.startswith("busy"))


def _wait(future, timeout: float) -> bool:
    done = threading.Event()
    future.add_done_callback(lambda _: done.set())
    return done.wait(timeout) or future.done()


class Client:
    """A thread's client: its own rclpy Context, node and executor (spun on a thread)."""

    def __init__(self, name: str, domain_id: int):
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id,
                   signal_handler_options=SignalHandlerOptions.NO)
        self.node = Node(name, context=self.context)
        self.service = self.node.create_client(PlanGait, SERVICE)
        self.action = ActionClient(self.node, PlanGaitAction, ACTION)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self.executor.spin, daemon=True)
        self.thread.start()

    def ready(self, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.service.service_is_ready() and self.action.server_is_ready():
                return True
            time.sleep(0.05)
        return False

    def call(self, request: PlanGait.Request, timeout: float) -> Answer:
        answer = Answer("service", request, time.monotonic())
        future = self.service.call_async(request)
        if _wait(future, timeout):
            answer.done, answer.response = time.monotonic(), future.result()
        return answer

    def goal(self, goal: PlanGaitAction.Goal, timeout: float, cancel_after: float | None,
             on_accepted: Callable[[], None] | None = None) -> Answer:
        answer = Answer("action", goal, time.monotonic())
        # Sent from the executor's thread: rclpy 9.1.2's send_goal_async stores a second
        # future outside its lock after sending, so a goal response that the spinning thread
        # takes in between completes a discarded future and the returned one never
        # completes (ros2/rclpy#1123; seen here: a goal accepted and executed, no answer).
        task = self.executor.create_task(lambda: self.action.send_goal_async(
            goal, feedback_callback=lambda m: answer.feedback.append(
                (time.monotonic(), m.feedback.phase))))
        if not _wait(task, timeout) or not _wait(sent := task.result(), timeout):
            return answer
        handle = sent.result()
        answer.accepted = handle.accepted
        if not handle.accepted:
            answer.done = time.monotonic()
            return answer
        answer.accepted_at = time.monotonic()
        result = handle.get_result_async()
        if on_accepted is not None:
            on_accepted()
        if cancel_after is not None and not _wait(result, cancel_after):
            answer.cancel_phase = answer.feedback[-1][1] if answer.feedback else ""
            answer.cancel_sent = time.monotonic()
            cancel = handle.cancel_goal_async()
        if _wait(result, timeout):
            answer.done = time.monotonic()
            answer.status, answer.response = result.result().status, result.result().result
        if answer.cancel_sent is not None and _wait(cancel, FAST):
            answer.cancel_accepted = bool(cancel.result().goals_canceling)
        return answer

    def send(self, via: str, request: dict, timeout: float, **goal_options) -> Answer:
        if via == "service":
            return self.call(PlanGait.Request(**request), timeout)
        return self.goal(PlanGaitAction.Goal(**request), timeout, **goal_options)

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=5)
        self.action.destroy()
        self.node.destroy_node()
        self.context.try_shutdown()
        self.thread.join(5)


# ------------------------------------------------------------------- the node and its world

def _tree(root: Path, skip: tuple[str, ...] = ()) -> dict[str, tuple[int, int]]:
    """relative path -> (mtime_ns, size) of the files under root (skipping SKIPPED_DIRS,
    *.egg-info and the relative folders `skip`)."""
    files: dict[str, tuple[int, int]] = {}
    for folder, dirs, names_ in os.walk(root):
        rel = Path(folder).relative_to(root)
        dirs[:] = [d for d in dirs if d not in SKIPPED_DIRS and not d.endswith(".egg-info")
                   and (rel / d).as_posix() not in skip]
        for name in names_:
            try:
                stat = (Path(folder) / name).lstat()
            except OSError:
                continue
            files[(rel / name).as_posix()] = (stat.st_mtime_ns, stat.st_size)
    return files


def _listing(folder: Path) -> set[str]:
    try:
        return set(os.listdir(folder))
    except OSError:
        return set()


@dataclass
class Live:
    process: subprocess.Popen
    output: Path
    clients: list[Client]
    log: Path
    before: dict
    stats: Counter = field(default_factory=Counter)
    slowest: list = field(default_factory=list)  # (elapsed / allowance, elapsed, allowance, what)
    bare: list = field(default_factory=list)  # the same against limit + GRACE alone (plans)
    built: set = field(default_factory=set)  # problem keys the node has built
    recorded: dict = field(default_factory=dict)  # mcap path -> output_name asked for
    sent_names: set = field(default_factory=set)
    planned_once: bool = False
    started: float = field(default_factory=time.monotonic)

    def node_log_tail(self) -> str:
        return self.log.read_text(errors="replace")[-3000:]


def _world(output: Path) -> dict:
    """What is compared before and after: the repository tree, the pytest temporary root
    (the output folder's parent) and /tmp's top level."""
    return {"repo": _tree(REPO, SHARED), "basetemp": _listing(output.parent),
            "tmp": _listing(Path("/tmp")), "output_files": _listing(output)}


@pytest.fixture(scope="module")
def live(ros_domain_id: int, tmp_path_factory: pytest.TempPathFactory):
    """One `gait-planner node` process for the module, and four clients."""
    output = tmp_path_factory.mktemp("fuzz_out")
    log = tmp_path_factory.mktemp("fuzz_node") / "node.log"
    before = _world(output)
    with open(log, "wb") as stream:
        process = subprocess.Popen(
            [str(GAIT_PLANNER), "node", "--ros-args", "-p", f"output_dir:={output}",
             "-p", f"allowed_output_dirs:=[{output}]", "-p", f"default_scene:={DEFAULT_SCENE}",
             "-p", "prepare_on_start:=false", "-p", f"max_solve_time:={NODE_MAX_SOLVE_TIME}",
             "-p", "warm_start_store:=false"],
            cwd=REPO, stdout=stream, stderr=subprocess.STDOUT)
    clients: list[Client] = []
    state = Live(process, output, clients, log, before)
    try:
        clients.extend(Client(f"gait_planner_fuzz_{i}", ros_domain_id) for i in range(4))
        for client in clients:
            assert client.ready(60), f"the node's service/action not discovered:\n" \
                                     f"{state.node_log_tail()}"
        yield state
    finally:
        for client in clients:
            client.close()
        if process.poll() is None:
            process.terminate()
            try:
                process.wait(10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(10)


# ---------------------------------------------------------------------------- the checks

def _allowance(live: Live, request, planned: bool, found: bool) -> float:
    """The longest an answer to `request` may take (module docstring)."""
    if not planned:
        return FAST
    allowance = GRACE + solve_limit(request)
    key = problem_key(request)
    if key not in live.built:
        allowance += BUILD_ALLOWANCE
    if found:
        allowance += RECORD_ALLOWANCE + RECORD_PER_STEP * steps_of(request)
    if not live.planned_once:
        allowance += FIRST_ALLOWANCE
    return allowance


def _check(live: Live, answer: Answer) -> str:
    """Assert everything about one answer; return its category for the counts."""
    what = f"{answer.via} {as_received(answer.request)!r}"[:600]
    assert live.process.poll() is None, f"the node died on {what}:\n{live.node_log_tail()}"
    refusal = predicted_refusal(answer.request)
    planned = refusal is None
    limit_if_found = _allowance(live, answer.request, planned, True)
    assert answer.done is not None, (
        f"no answer within {answer.elapsed:.1f} s (limit {limit_if_found:.1f} s) to {what}")

    if answer.busy:  # answered at once, before any check of the request
        assert answer.elapsed <= FAST, f"busy after {answer.elapsed:.2f} s: {what}"
        if answer.via == "service":
            assert answer.response.message == BUSY and not answer.response.success
        live.stats["busy" if answer.via == "service" else "rejected"] += 1
        live.slowest.append((answer.elapsed / FAST, answer.elapsed, FAST, "busy " + what))
        return "busy"

    response = answer.response
    if answer.via == "action":
        assert answer.accepted
        expected = (GoalStatus.STATUS_SUCCEEDED if response.success else
                    GoalStatus.STATUS_CANCELED if response.message == STOPPED
                    else GoalStatus.STATUS_ABORTED)
        assert answer.status == expected, (answer.status, response.message, what)
        if answer.cancel_sent is not None:  # the cancel's answer agrees with the outcome
            assert answer.cancel_accepted is not None, f"no answer to the cancel: {what}"
            if answer.status == GoalStatus.STATUS_CANCELED:
                assert answer.cancel_accepted, f"canceled, but the cancel was refused: {what}"
            if answer.status == GoalStatus.STATUS_SUCCEEDED:
                assert not answer.cancel_accepted, f"cancel accepted, plan recorded: {what}"

    if not response.success:
        assert response.message, f"a refusal without a message: {what}"
        assert "internal error" not in response.message, f"{response.message}: {what}"
    if refusal is not None:
        assert not response.success, f"planned although {refusal!r}: {what}"
        assert response.message == refusal, (response.message, refusal, what)
        assert any(name in refusal for name in FIELDS), refusal
        assert answer.elapsed <= FAST, f"refused after {answer.elapsed:.2f} s: {what}"
        assert not response.mcap_path
        live.stats["refused"] += 1
        live.stats["refused: " + min((n for n in FIELDS if n in refusal), key=refusal.index)] += 1
        live.slowest.append((answer.elapsed / FAST, answer.elapsed, FAST, "refused " + what))
        return "refused"

    # planned: found, failed (solver) or stopped (cancel)
    allowance = _allowance(live, answer.request, True, response.success)
    bare = solve_limit(answer.request) + GRACE
    live.bare.append((answer.elapsed / bare, answer.elapsed, bare,
                      f"{'found' if response.success else 'not found'} {what}"))
    live.slowest.append((answer.elapsed / allowance, answer.elapsed, allowance,
                         f"{'found' if response.success else 'not found'} {what}"))
    if answer.feedback and answer.accepted_at is not None:
        # the solve alone (after building, before recording) keeps the limit + GRACE
        phases = answer.feedback
        start = next((t for t, p in phases if p and not p.startswith("building")), None)
        end = next((t for t, p in phases if p == "recording"), answer.done)
        if start is not None:
            solve = end - start
            assert solve <= solve_limit(answer.request) + GRACE, (
                f"solve took {solve:.2f} s, limit {solve_limit(answer.request)} s: {what}")
            built = start - answer.accepted_at
            if problem_key(answer.request) not in live.built:
                live.stats["max build (s)"] = max(live.stats["max build (s)"], round(built, 3))
            if response.success:
                record = answer.done - end
                live.stats["max record per step (s)"] = max(
                    live.stats["max record per step (s)"],
                    round(record / steps_of(answer.request), 3))
    assert answer.elapsed <= allowance, (
        f"answer after {answer.elapsed:.2f} s, allowed {allowance:.2f} s: {what}")
    live.built.add(problem_key(answer.request))
    live.planned_once = True

    if response.message == STOPPED:
        assert answer.via == "action" and answer.cancel_sent is not None, what
        assert not response.mcap_path
        latency = answer.done - answer.cancel_sent
        building = answer.cancel_phase == "" or (answer.cancel_phase or "").startswith("building")
        bound = FAST + (BUILD_ALLOWANCE if building else 0)
        assert latency <= bound, f"canceled {latency:.2f} s after the cancel: {what}"
        live.stats["canceled"] += 1
        return "canceled"
    if not response.success:
        assert not response.mcap_path
        assert response.message.startswith("IPOPT"), response.message
        live.stats["not found (solver)"] += 1
        live.stats[f"not found: {response.solver_status}"] += 1
        return "failed"

    path = Path(response.mcap_path)
    assert path.parent == live.output and path.suffix == ".mcap", path
    assert path.resolve().parent == live.output.resolve(), path
    recorded = read_plan_mcap(path)
    assert len(recorded.time_from_start) == len(response.trajectory.points), path
    asked = received(answer.request.output_name)
    if str(path) in live.recorded:
        assert asked and live.recorded[str(path)] == asked, (
            f"{path} was already the recording of an earlier plan (asked "
            f"{live.recorded[str(path)]!r}); now {what} overwrote it")
    live.recorded[str(path)] = asked
    live.stats["accepted"] += 1
    live.stats["canceled too late (found)"] += answer.cancel_sent is not None
    return "accepted"


# an .rrd being written (`gait_planner.atomic.atomic_target`): group 1 is its file name
_RRD_TEMPORARY = re.compile(r"\.(.+\.rrd)\.[0-9]{1,9}\.[0-9a-f]{12}\.tmp")


def _check_output_folder(live: Live) -> None:
    """Only the recordings of answered plans, and the temporaries of .rrd files still being
    written (`gait_planner.viz.rrd_recorder` writes them after the answer)."""
    allowed = set()
    for path in live.recorded:
        stem = Path(path).stem
        allowed |= {f"{stem}.mcap", f"{stem}.rrd"}
    present = _listing(live.output) - live.before["output_files"]
    unexpected = {name for name in present - allowed
                  if not ((m := _RRD_TEMPORARY.fullmatch(name)) and m[1] in allowed)}
    assert not unexpected, f"unexpected files in the output folder: {unexpected}"


@seed(20261123)  # the same requests every run (derandomize=True ran out of examples)
@settings(max_examples=EXAMPLES, database=None, deadline=None,
          phases=(Phase.explicit, Phase.generate), report_multiple_bugs=False,
          suppress_health_check=list(HealthCheck))
@given(scenario=scenarios())
# a scene name of bare-name characters too long for a file name: the node answered with the
# file system's "[Errno 36] File name too long: '<path>'" (no field named) before the fix
@example(scenario=Scenario({**QUIET, "scene": "0" * 300}, "service", None))
@example(scenario=Scenario({**QUIET, "scene": "compass\0/../../x",
                            "output_name": "fuzz_nul\0/../../escape"}, "action", 0.0))
def test_fuzz_live_node_answers_every_request(live: Live, scenario: Scenario):
    primary, others = live.clients[0], live.clients[1:1 + len(scenario.others)]
    live.sent_names |= {received(r["output_name"]) for _, r in
                        [(scenario.via, scenario.request), *scenario.others]}
    long_wait = GRACE + MAX_PLAN_TIME + NODE_MAX_SOLVE_TIME + BUILD_ALLOWANCE + \
        RECORD_ALLOWANCE + RECORD_PER_STEP * MAX_STEPS + FIRST_ALLOWANCE + WAIT_EXTRA
    side: list[Answer] = []
    threads: list[threading.Thread] = []

    def fire() -> None:  # the other clients send at once, while the goal runs
        barrier = threading.Barrier(len(others))

        def send(client: Client, via: str, request: dict) -> None:
            barrier.wait(5)
            side.append(client.send(via, request, long_wait, cancel_after=None))

        for client, (via, request) in zip(others, scenario.others):
            threads.append(threading.Thread(target=send, args=(client, via, request)))
            threads[-1].start()

    first = primary.send(scenario.via, scenario.request, long_wait,
                         **({} if scenario.via == "service" else {
                             "cancel_after": scenario.cancel_after,
                             "on_accepted": fire if others else None}))
    if others and not first.accepted:  # rejected: nothing was fired
        fire()
    for thread in threads:
        thread.join(long_wait + 5)
    live.stats["requests"] += 1 + len(side)
    live.stats[f"via {scenario.via}"] += 1
    live.stats["cancels sent"] += first.cancel_sent is not None

    _check(live, first)
    for answer in side:
        if (first.accepted and first.done is not None
                and answer.sent < first.done - OVERLAP_MARGIN):
            # sent while the goal surely ran: must be answered busy at once, not queued
            said = answer.response.message if answer.response else None
            assert answer.busy, f"{answer.via} answered {said!r} while a goal ran"
            live.stats["busy while a goal ran"] += 1
        live.stats[f"side {answer.via}"] += 1
        _check(live, answer)
    assert len(side) == len(scenario.others)
    _check_output_folder(live)


def test_fuzz_wrote_nothing_outside_the_output_folder(live: Live, tmp_path_factory):
    """Stop the node, then compare the world with its state before the node started; print
    and store the counts of the fuzz run."""
    assert live.process.poll() is None, f"the node died:\n{live.node_log_tail()}"
    live.process.terminate()
    code = live.process.wait(10)
    assert code in (0, -15), f"node exit code {code}:\n{live.node_log_tail()}"
    after = _world(live.output)
    before = live.before

    names_sent = {n for n in live.sent_names if len(n) >= 3} | {
        "mcap", "rrd", "passwd", "escape", "fuzz", "compass_", "walker"}

    def node_like(name: str) -> bool:
        base = name.rsplit("/", 1)[-1]
        return base.endswith((".mcap", ".rrd", ".tmp")) or any(n in base for n in names_sent)

    # The repository: nothing the node could have written (a recording, a temporary, a
    # name it was sent), no new file at the top level (the node's working folder), nothing
    # new or changed in runs/ or config/. Other changes are other people's edits meanwhile
    # (listed in the summary).
    repo_changes = sorted(
        path for path in set(before["repo"]) | set(after["repo"])
        if before["repo"].get(path) != after["repo"].get(path)
        and path != "test/ros/test_fuzz.py")
    suspicious = [path for path in repo_changes if node_like(path)
                  or path.startswith(("runs/", "config/"))
                  or ("/" not in path and path not in before["repo"])]
    new_temp = sorted(after["basetemp"] - before["basetemp"])
    new_tmp = sorted(after["tmp"] - before["tmp"])
    node_tmp = [n for n in new_tmp if node_like(n) and not n.startswith("pytest")]

    def worst(entries: list) -> list:
        return [{"ratio": round(r, 3), "elapsed_s": round(e, 3), "allowed_s": round(a, 3),
                 "what": w[:300]} for r, e, a, w in sorted(entries, reverse=True)[:3]]

    summary = {"examples": EXAMPLES, "wall_time_s": round(time.monotonic() - live.started, 1),
               "counts": dict(sorted(live.stats.items())),
               "slowest_relative_to_allowance": worst(live.slowest),
               "slowest_plans_relative_to_limit_plus_1s": worst(live.bare),
               "other_new_tmp_entries": new_tmp[:50],
               "other_repo_changes": [p for p in repo_changes if p not in suspicious][:50]}
    path = tmp_path_factory.getbasetemp() / "fuzz_summary.json"
    path.write_text(json.dumps(summary, indent=1, default=str))
    print(f"\nfuzz summary ({path}):\n{json.dumps(summary, indent=1, default=str)}")

    assert not suspicious, f"files changed or new in the repository: {suspicious[:20]}"
    # pytest's own folders for this module's tests
    assert all(name.startswith(("test_fuzz", "fuzz_", "ros_log")) for name in new_temp), new_temp
    assert not node_tmp, f"new entries in /tmp that look like the node's: {node_tmp}"
