"""The ROS 2 node ``gait_planner``: service and action ``/gait_planner/plan_gait`` -> plan
-> topics.

Thin adapter: a request is converted to a `PlanRequest` (`gait_planner.request.plan_request`:
0 or empty fields take the node's or the scene's defaults, a negative, NaN or infinite number
is refused naming the field), planned and recorded by `gait_planner.pipeline`, and the plain
result is converted to messages by `gait_planner.io.messages` (the one module that owns
message layouts). Bad requests and failed plans are answered with success = False and a
message; the node keeps serving.

One plan at a time (`gait_planner.ros.worker`): a service request that arrives while a plan
runs is answered at once with success = False and a message starting "busy"; a goal of the
action (`gait_planner.ros.action_server`, feedback and cancel) is rejected. Parameters:
`gait_planner.ros.parameters` (typed, ranged, checked when set; ``config/gait_planner.yaml``).
Topics (reliable; volatile so a restarting controller never re-runs an old plan):
``/gait_planner/joint_trajectory`` (one message per plan), ``/gait_planner/state`` and
``/gait_planner/contact_forces`` (one message per node). A plan is answered once its MCAP
recording is written and its topics are published; its rerun recording (.rrd, same stem)
follows from a helper process (`gait_planner.viz.rrd_recorder`; "wrote the rerun
recording" in the log). With the parameter walk_steps > 0 the recorded plan is then walked
in MuJoCo (`gait_planner.walk`; action phase "walking", then "walking (k of K half cycles
done)" at each half cycle's end) before the answer, which carries how it went (walk_*
fields; a fall or a walk that cannot run leaves the plan's success as it is), and the walk's
summary is logged. A request's `start` ("state": the state it carries; "robot": the node's
latest ``/joint_states`` and the world -> root transform of ``/tf``, which the node
subscribes to, best effort) plans a transition onto the gait first
(`gait_planner.transitions`; converted by `gait_planner.io.messages.requested_start`), and
the answer and the topics are stamped with the start state's stamp; a start that cannot be
used, or a robot state not yet received, is refused naming why. SIGINT and SIGTERM stop a running solve within one
iteration and end the node (`main`); a killed node leaves the ROS graph within 3 s (its DDS
lease: `DDS_PROFILE`), so its clients stop waiting for it. At start the node removes
temporary recording files that killed processes left in its output folder.

Preparation: with prepare_on_start the node builds the default request's problem before it
offers its service, then prepares the scenes of prepare_scenes in the background
(`gait_planner.ros.preparation`, progress in the log); the service
``/gait_planner/preparation`` (`gait_planner_msgs/srv/Preparation`) answers what is ready and
what is not yet. A request for a scene not yet prepared is planned all the same (its
problem built, and compiled if need be, for it) and its answer's message says so.
"""

from __future__ import annotations

import functools
import os
import sys
import time
from pathlib import Path
from typing import Callable

import rclpy
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data

from gait_planner.gaitlib.index import LibraryError
from gait_planner.gaitlib.serve import library_start
from gait_planner.io import messages
from gait_planner.atomic import remove_stale_temporaries
from gait_planner.viz.rrd_recorder import RrdRecorder
from gait_planner.model.loader import SceneError, load_scene, scene_dirs
from gait_planner.model.urdf_errors import UrdfError
from gait_planner.ocp.warm_starts import WarmStartStore
from gait_planner.ocp.solve import STOPPED, Planner
from gait_planner.ocp.transition import StartError
from gait_planner.result import PlanStatus
from gait_planner.pipeline import plan_and_record, prepare
from gait_planner.problem import resolve
from gait_planner.request import PlanRequest, RequestError, plan_request
from gait_planner.ros import parameters
from gait_planner.ros.action_server import PlanGaitActionServer
from gait_planner.ros.preparation import BackgroundPreparation
from gait_planner.ros.robot_description import RobotScenes
from gait_planner.ros.worker import Closed, Lapsed, PlanWorker, Stopped
from gait_planner.transitions import HALVES, MAX_HALVES, STOP_HALVES
from gait_planner.walk.walk_plan import walk
from gait_planner.walk.summary import format_summary, half_cycles_done
from gait_planner_msgs.msg import ContactForces, MultibodyState
from gait_planner_msgs.srv import PlanGait, Preparation
from sensor_msgs.msg import JointState
from std_msgs.msg import String

try:
    from tf2_msgs.msg import TFMessage
except ImportError:  # ROS 2 wheels from PyPI without `make setup`'s tools/tf2_msgs
    TFMessage = None
from trajectory_msgs.msg import JointTrajectory

SERVICE = "/gait_planner/plan_gait"
PREPARATION_SERVICE = "/gait_planner/preparation"
TOPIC_TRAJECTORY = "/gait_planner/joint_trajectory"
TOPIC_STATE = "/gait_planner/state"
TOPIC_FORCES = "/gait_planner/contact_forces"
TOPIC_DESCRIPTION = "/robot_description"  # a robot's URDF, drafted into a scene on arrival
TOPIC_JOINT_STATES = "/joint_states"  # the robot's measured joints (PlanGait start "robot")
TOPIC_TF = "/tf"  # its world -> root transform (start "robot")
BUSY = "busy: another plan is running (the node plans one request at a time); try again later"
EXECUTOR_THREADS = 4  # a waiting plan request holds one; busy answers and cancels need others
EXIT_GRACE = 0.5  # s a stopped plan gets to end at shutdown before the process leaves anyway
RECORDING_GRACE = 10.0  # s the .rrd files still being written get at shutdown
SHUTDOWN_POLL = 0.1  # s between checks that the context is still up (see main)
# Fast DDS profile of the node's participant: a 3 s lease, so that a killed node leaves the
# ROS graph (and its clients give up: gait_planner.ros.client) within seconds, not 20 s
DDS_PROFILE = Path(__file__).with_name("fastdds_profile.xml")


class GaitPlannerNode(Node):
    """Serves plan requests (service and action) one at a time; a request that arrives
    while a plan runs is answered "busy" at once. `planner` replaces the node's own (tests);
    the node's stage and stop hooks are then not wired to it."""

    def __init__(self, *, planner: Planner | None = None, **kwargs):
        # (destroy_node may run before __init__ has ended)
        self._worker, self._action, self._recorder = PlanWorker(), None, None
        self._preparation = BackgroundPreparation([], lambda line: None)  # none yet
        # the robot's latest /joint_states and world -> frame transforms (start "robot")
        self._joint_state, self._transforms = None, {}
        super().__init__("gait_planner", **kwargs)
        self._worker.on_lapse = self._on_lapse
        parameters.declare(self)
        folders = list(self._param("scene_dirs"))  # read-only: fixed for the node's life
        self._scenes = RobotScenes(functools.partial(load_scene, extra=folders),
                                   lambda: Path(self._param("output_dir")),
                                   [d for d in self._param("robot_package_dirs") if d],
                                   self._param("robot_mirror_tolerance"))
        missing = [f for f in folders if not Path(f).expanduser().is_dir()]
        if missing:
            self.get_logger().info(f"scene_dirs: no folder {missing} (skipped); scenes from "
                                   f"{[str(d) for d in scene_dirs(folders)]}")
        for path in remove_stale_temporaries(self._param("output_dir")):
            self.get_logger().info(f"removed the stale temporary file {path}")
        self._recorder = RrdRecorder()  # its helper imports rerun while the problem is built
        use_store = self._param("warm_start_store")
        if not self._param(parameters.DEPRECATED_STORE):
            self.get_logger().warning(f"the parameter {parameters.DEPRECATED_STORE} is "
                                      "deprecated: use warm_start_store (the same meaning)")
            use_store = False
        library = WarmStartStore() if use_store else None
        self._planner = planner or Planner(progress=self._progress, stage=self._worker.enter,
                                           stop=self._worker.stopped, library=library)
        if self._param("prepare_on_start"):
            self._prepare()
            self._preparation = BackgroundPreparation(
                self._scenes_to_prepare(folders), self.get_logger().info, folders)
        group = ReentrantCallbackGroup()
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self._pub_trajectory = self.create_publisher(JointTrajectory, TOPIC_TRAJECTORY, 10)
        self._pub_state = self.create_publisher(MultibodyState, TOPIC_STATE, qos)
        self._pub_forces = self.create_publisher(ContactForces, TOPIC_FORCES, qos)
        self.create_service(PlanGait, SERVICE, self._on_plan, callback_group=group)
        self.create_service(Preparation, PREPARATION_SERVICE, self._on_preparation,
                            callback_group=group)
        self._describe(self._param("robot_description"), "the parameter robot_description")
        self.add_post_set_parameters_callback(self._on_parameters)
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.create_subscription(String, TOPIC_DESCRIPTION,
                                 lambda msg: self._describe(msg.data, TOPIC_DESCRIPTION),
                                 latched, callback_group=group)
        # best effort: matches a reliable publisher as well as a sensor-data one
        self.create_subscription(JointState, TOPIC_JOINT_STATES, self._on_joint_state,
                                 qos_profile_sensor_data, callback_group=group)
        if TFMessage is None:
            self._transforms = None  # start "robot" is refused saying why
            self.get_logger().warning("tf2_msgs is not installed (make setup builds it): no "
                                      "/tf subscription, start \"robot\" is refused")
        else:
            self.create_subscription(
                TFMessage, TOPIC_TF, self._on_tf,
                QoSProfile(depth=100, reliability=ReliabilityPolicy.BEST_EFFORT),
                callback_group=group)
        self._action = PlanGaitActionServer(self, self._worker, self._plan_into, group)
        self._preparation.start()

    def _on_joint_state(self, msg: JointState) -> None:
        self._joint_state = msg

    def _on_tf(self, msg: TFMessage) -> None:
        """Keep the latest transform from the world frame to each frame (start "robot")."""
        transforms = dict(self._transforms)
        for transform in msg.transforms:
            if transform.header.frame_id.lstrip("/") == messages.WORLD_FRAME:
                transforms[transform.child_frame_id.lstrip("/")] = transform
        self._transforms = transforms

    def _describe(self, urdf: str, source: str) -> None:
        """Draft the robot of a URDF text (`RobotScenes.describe`); errors are logged, the
        node keeps serving (requests for the robot then answer why)."""
        if not urdf.strip():
            return
        try:
            note = self._scenes.describe(urdf)
        except (UrdfError, SceneError, OSError) as err:
            self.get_logger().error(f"{source}: {err}")
            return
        if note:
            self.get_logger().info(f"{source}: {note}")

    def _on_parameters(self, changed: list) -> None:
        for parameter in changed:
            if parameter.name == "robot_description":
                self._describe(parameter.value, "the parameter robot_description")

    def _prepare(self) -> None:
        """Build the default request's problem (parameter prepare_on_start); a failure
        only costs the first request its build."""
        start = time.perf_counter()
        request = PlanRequest(scene=self._param("default_scene"),
                              compiled=self._param("compile_derivatives"))
        try:
            how = prepare(self._planner, resolve(request, self._scenes), rrd=False)
        except (RequestError, ValueError, RuntimeError) as err:
            self.get_logger().warning(f"could not prepare {request.scene}: {err}")
            return
        self.get_logger().info(f"prepared {request.scene} in {time.perf_counter() - start:.1f} s"
                               f" ({how})")

    def _scenes_to_prepare(self, folders: list[str]) -> list:
        """The scenes of prepare_scenes (an unknown one logged and left out)."""
        scenes = []
        for name in dict.fromkeys(n for n in self._param("prepare_scenes") if n):
            try:
                scenes.append(load_scene(name, extra=folders))
            except SceneError as err:
                self.get_logger().warning(f"prepare_scenes: {err}")
        return scenes

    def _on_preparation(self, request: Preparation.Request, response: Preparation.Response):
        status = self._preparation.status()
        response.done, response.message = status.done, status.message
        response.ready, response.pending = list(status.ready), list(status.pending)
        return response

    def close(self) -> None:
        """Stop a running plan and the background preparation, and release the callbacks
        waiting for the plan (shutdown)."""
        self._preparation.close()
        self._worker.close()

    def wait_idle(self, timeout: float) -> bool:
        """Wait up to `timeout` s for a running plan to end; True if none runs."""
        return self._worker.wait_idle(timeout)

    def destroy_node(self) -> None:
        """Stop a running plan, wait up to `RECORDING_GRACE` s for the .rrd files being
        written, then destroy the action server and the node."""
        self.close()
        if self._recorder is not None and not self._recorder.close(RECORDING_GRACE):
            self.get_logger().warning("shutting down with .rrd files still being written")
        if self._action is not None:
            self._action.destroy()
        super().destroy_node()

    def _progress(self, iteration: int, cost: float, violation: float, seconds: float) -> None:
        self._worker.progress(iteration, cost, violation)
        if iteration % 25 == 0:
            self.get_logger().info(
                f"iteration {iteration}: cost {cost:.6g}, constraint violation "
                f"{violation:.2e}, {seconds:.1f} s")

    def _param(self, name: str):
        return self.get_parameter(name).value

    def _on_plan(self, request: PlanGait.Request, response: PlanGait.Response):
        ticket = self._worker.try_reserve()
        if ticket is None:
            response.success, response.message = False, BUSY
            self.get_logger().warning("plan request answered busy")
            return response
        try:
            self._worker.run(ticket, lambda: self._plan_into(request, response))
        except (Closed, Lapsed) as err:
            response.success, response.message = False, str(err)
        return response

    def _on_lapse(self, ticket: int, age: float) -> None:
        self.get_logger().warning(
            f"request {ticket}, accepted {age:.1f} s ago, never started (its acceptance did not "
            "reach the client); the node takes the next request")

    def _plan_into(self, request, answer) -> PlanStatus | None:
        """Plan `request` (service request or action goal), record and publish the plan,
        and fill `answer` (service response or action result: the same fields); how the
        plan ended (None: refused, or an internal error). Runs in the worker's plan
        thread."""
        walk_steps = int(self._param("walk_steps"))  # as set when the request arrived
        try:
            problem = resolve(plan_request(  # 0 or empty fields: the node's or the scene's
                request, default_scene=self._param("default_scene"),
                default_max_solve_time=self._param("max_solve_time"),
                compiled=self._param("compile_derivatives")), self._scenes)
            stop = bool(request.stop)
            halves = _half_cycles(request.transition_half_cycles, stop)
            start, start_ns = messages.requested_start(problem.scene, request,
                                                       self._joint_state, self._transforms)
            library = self._param("gait_library")
            seed, note = (None, "") if (not library or not problem.warm_start
                                        or start is not None or stop) else library_start(
                self._planner, Path(library).expanduser(), problem, self._scenes)
            if not self._preparation.ready(problem.scene.name):
                note = "; ".join(filter(None, [note, (
                    f"{problem.scene.name} is not prepared yet ({PREPARATION_SERVICE} says "
                    "how far): this request built its own problem")]))
            outcome = plan_and_record(self._planner, problem, self._param("output_dir"),
                                      rrd=False, stage=self._worker.enter, seed=seed,
                                      start=start, halves=halves, stop=stop)
        except Stopped:
            answer.success, answer.message = False, self._stopped_message()
            self.get_logger().info(f"{answer.message}: nothing recorded")
            return PlanStatus.STOPPED
        except (RequestError, StartError, LibraryError, OSError) as err:
            answer.success, answer.message = False, str(err)
            self.get_logger().warning(f"plan request refused: {err}")
            return None
        except Exception as err:  # noqa: BLE001  (a bug must not stop the service)
            answer.success = False
            answer.message = f"internal error ({type(err).__name__}): {err}"
            self.get_logger().error(f"plan request failed: {answer.message}")
            return None
        result = outcome.result
        stopped = result.status is PlanStatus.STOPPED
        # a transition is stamped with its start state's time (where a controller splices
        # it in); the periodic gait (or a state without a stamp) with the answer's
        stamp = start_ns or self.get_clock().now().nanoseconds
        messages.fill_message(answer, messages.plan_response_fields(
            result, str(outcome.mcap_path or ""), stamp) if result.success else {
                "success": False,
                "message": self._stopped_message() if stopped else result.message,
                "solver_status": result.stats.status})
        if note:
            answer.message = f"{answer.message} ({note})"
            self.get_logger().info(note)
        if result.success:
            self._recorder.submit(result, outcome.mcap_path.with_suffix(".rrd"), self._recorded)
            self._publish(result, stamp)
            self.get_logger().info(
                f"planned {result.scene.name}: cost {result.cost_value:.6g}, duration "
                f"{result.duration:.4f} s, recorded {outcome.mcap_path}")
            if walk_steps:
                messages.fill_message(answer, self._walk(outcome.mcap_path, walk_steps))
        elif stopped:
            self.get_logger().info(f"{answer.message}: nothing recorded")
        else:
            self.get_logger().warning(f"plan failed: {result.message}")
        return result.status

    def _walk(self, mcap_path: Path, steps: int) -> dict:
        """Walk the recorded plan `steps` half cycles in MuJoCo (parameter walk_steps; phase
        "walking", in the plan thread; each half cycle's end is told as the phase "walking (k
        of K half cycles done)") and return the answer's walk fields; a walk that cannot run
        is told there and in the log, never raised."""
        self._worker.enter("walking")
        try:
            walked = walk(mcap_path, steps, progress=lambda k, n: self._worker.detail(
                half_cycles_done(k, n)))
        except ValueError as err:  # the plan cannot be walked, e.g. a scene without feet
            self.get_logger().warning(f"could not walk the plan: {err}")
            return messages.walk_response_fields(steps, None, str(err))
        except Exception as err:  # noqa: BLE001  (a bug of the walk must not stop the service)
            error = f"internal error ({type(err).__name__}): {err}"
            self.get_logger().error(f"could not walk the plan: {error}")
            return messages.walk_response_fields(steps, None, error)
        self.get_logger().info(f"walked the plan: {format_summary(walked)}")
        return messages.walk_response_fields(steps, walked)

    def _stopped_message(self) -> str:
        """Why a plan stopped: a cancel (`STOPPED`), or the node's shutdown."""
        return ("stopped: the node is shutting down (SIGINT or SIGTERM)"
                if self._worker.closing() else STOPPED)

    def _recorded(self, path, error) -> None:
        """The helper's report on a plan's .rrd (`RrdRecorder.submit`)."""
        if error is None:
            self.get_logger().info(f"wrote the rerun recording {path}")
        else:
            self.get_logger().warning(f"no rerun recording written: {error}")

    def _publish(self, result, start_ns: int) -> None:
        self._pub_trajectory.publish(messages.fill_message(
            JointTrajectory(), messages.joint_trajectory(result, start_ns)))
        for state in messages.multibody_states(result, start_ns):
            self._pub_state.publish(messages.fill_message(MultibodyState(), state))
        for forces in messages.contact_forces(result, start_ns):
            self._pub_forces.publish(messages.fill_message(ContactForces(), forces))


def _half_cycles(value: int, stop: bool = False) -> int:
    """PlanGait's transition_half_cycles: 0 is `HALVES` (a stop's `STOP_HALVES`);
    RequestError outside 1..MAX_HALVES."""
    if value == 0:
        return STOP_HALVES if stop else HALVES
    if not 1 <= value <= MAX_HALVES:
        raise RequestError(f"transition_half_cycles must be 1 to {MAX_HALVES}, or 0 for "
                           f"{HALVES}, got {value}")
    return int(value)


def serve(node: GaitPlannerNode, executor: MultiThreadedExecutor,
          until: Callable[[], bool] = lambda: False) -> None:
    """Spin `executor` (which serves `node`) until the node's context shuts down or `until()`.

    Not `executor.spin()`: its wait has no timeout, and a signal arriving while the executor
    builds its wait set was seen lost (the wait never woke; 1 in ~25 runs). An answer that
    cannot be sent does not end the service: rclpy raises an RCLError from the callback's
    task when sending fails (on Fast DDS's timeout for a client whose response reader it
    has not discovered 100 ms after the request, rclpy 9.1.2 only warns)."""
    while node.context.ok() and not until():
        try:
            executor.spin_once(timeout_sec=SHUTDOWN_POLL)
        except _rclpy.RCLError as err:
            if not node.context.ok():  # a signal shut the context down during this turn
                return  # ("failed to initialize wait set": seen in CI)
            node.get_logger().warning(f"an answer could not be sent: {err}")


def _announce_short_lease() -> None:
    """Use `DDS_PROFILE` for the node's participant, unless another RMW than Fast DDS is
    chosen or the user gives Fast DDS a profile of their own (then a killed node leaves the
    graph when their lease ends)."""
    rmw = os.environ.get("RMW_IMPLEMENTATION") or "rmw_fastrtps_cpp"
    own = ("FASTDDS_DEFAULT_PROFILES_FILE", "FASTRTPS_DEFAULT_PROFILES_FILE")
    if rmw.startswith("rmw_fastrtps") and not any(os.environ.get(name) for name in own):
        os.environ["FASTDDS_DEFAULT_PROFILES_FILE"] = str(DDS_PROFILE)


def main(args=None) -> int:
    """Run the node until SIGINT or SIGTERM (``gait-planner node``). rclpy's signal
    handlers shut the context down, which ends the spin (within `SHUTDOWN_POLL` s); a
    running solve is then stopped within one iteration. A problem being built cannot be
    interrupted, and CasADi aborts the process if the interpreter is finalised under it:
    if the plan thread has not ended `EXIT_GRACE` s after the ROS shutdown, the process
    ends at once (`os._exit`; nothing is being written then, or only a temporary file,
    which the next start removes)."""
    _announce_short_lease()
    rclpy.init(args=args)
    try:
        node = GaitPlannerNode()
    except Exception:
        rclpy.try_shutdown()
        raise
    executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS)
    executor.add_node(node)
    node.get_logger().info(f"serving the service and the action {SERVICE}")
    try:
        serve(node, executor)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.close()
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    if not node.wait_idle(EXIT_GRACE):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)
    return 0
