"""Shared test setup: strict numerics, the `slow` marker, and cached models per scene.

* Floating-point trouble raises: every test runs under ``numpy.errstate(all="raise")``
  (division by zero, overflow and invalid operations become FloatingPointError; underflow,
  which is harmless round-off to zero, is ignored).
* ``@pytest.mark.slow`` marks the end-to-end tests that take ten seconds or more (long
  solves, refinements, walker3d's physical checks, the web viewer's screenshot): `make test`
  runs every other test (``-m "not slow"``, a few minutes on 2 cores), `make test-slow` runs
  these, and CI (`.ci/run`) runs both.
* After a slow test the freed heap goes back to the system (`_release_memory_after_slow_tests`).
* `make test` and `make test-slow` run the tests on two workers (pytest-xdist, `--dist
  loadfile`, TEST_WORKERS in the Makefile): each module's tests on one worker (its module
  fixtures built once), and the modules of `WHOLE_ROBOTS` one after another on one worker
  (`pytest_xdist_make_scheduler`), so that two whole-robot plans never share the machine's
  memory (two G1 plans side by side, 12 GB each, ran it out on 2026-12-07). The tests
  marked ``alone`` run after the rest, in one process: a re-planned walk charges each
  solve's wall time to the simulation, and beside another test the node's re-plans of
  walker2d arrived too late and its walk ran out of plan (2026-12-07); the node planning G1
  (test_node_robot) grew a CI worker to 24.3 GB, the machine's memory, after the robots
  before it on that worker (2026-12-07, cause not pinned down: alone it peaks at 12.6 GB;
  a refinement the machine has no memory for is no longer built, `strategies._no_room_for`).
* The `model` fixture returns a cached factory ``model(name) -> Model`` (scene, Multibody,
  DiscreteMechanics), so each scene's CasADi Functions are built once per session.
"""

from __future__ import annotations

import gait_planner  # noqa: F401  (first: pins numpy's BLAS kernels before numpy loads)

import functools
import gc
from importlib import metadata
from pathlib import Path
from typing import Callable, Iterator, NamedTuple

import numpy as np
import pytest

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.memory import release_free_heap
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.result import PlanResult
from synthetic_result import START_NS, make_result

SCENES = ("compass", "walker2d", "walker3d")
# The modules that plan robots from their URDFs (G1's plan peaks at 12 GB, iCub's at 6 GB)
WHOLE_ROBOTS = ("test/ocp/test_ocp_robot.py", "test/ocp/test_ocp_robot_axes.py",
                "test/ros/test_node_robot.py", "test/walk/test_walk_g1.py")


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "slow: an end-to-end test of ten seconds or more (make test-slow; CI runs it)"
    )
    config.addinivalue_line(
        "markers", "alone: needs this machine to itself (a re-planned walk charges its wall "
        "time to a simulation; the node planning G1 in its own process takes 12.6 GB): "
        "`make test-slow` runs it after the others, in one process, with no test beside it")


def pytest_xdist_make_scheduler(config: pytest.Config, log):
    """With `--dist loadfile`: each module one unit of work, the `WHOLE_ROBOTS` modules
    together one (xdist's own `loadgroup` does not group under pytest 9.2:
    pytest-dev/pytest-xdist#1386). xdist hands out the units with the most tests first, so
    the robots' unit, the slow suite's longest, starts first."""
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class OneRobotAtATime(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            module = nodeid.split("::", 1)[0]
            return "whole robots" if module in WHOLE_ROBOTS else module

    return OneRobotAtATime(config, log)


@pytest.fixture(autouse=True)
def strict_numerics() -> Iterator[None]:
    with np.errstate(all="raise", under="ignore"):
        yield


@pytest.fixture(autouse=True)
def _release_memory_after_slow_tests(request) -> Iterator[None]:
    """After a slow test (whole robots planned: G1's plan peaks at 12 GB), collect and
    return the freed heap to the system, so that the slow suite's one process does not
    keep the peaks of every robot before it (it held 19-20 GB of the machine's 24 when
    test_node_robot started another process planning G1, 2026-12-07)."""
    yield
    if request.node.get_closest_marker("slow") is not None:
        gc.collect()
        release_free_heap()


class Model(NamedTuple):
    scene: Scene
    mb: Multibody
    mech: DiscreteMechanics


@functools.cache
def _model(name: str) -> Model:
    scene = load_scene(name)
    mb = Multibody(scene)
    return Model(scene, mb, DiscreteMechanics(mb))


@pytest.fixture(scope="session")
def model() -> Callable[[str], Model]:
    """Factory: model("walker3d") -> Model(scene, mb, mech), cached for the session."""
    return _model


@pytest.fixture(scope="session", params=SCENES)
def any_model(request: pytest.FixtureRequest) -> Model:
    """Each scene of `SCENES` in turn."""
    return _model(request.param)


@pytest.fixture(scope="session")
def example_robots() -> Path:
    """The robots folder of the example-robot-data wheel (a test dependency pinned in
    requirements.txt: URDFs of Unitree G1, Talos, Bolt); the test is skipped without it.
    Its parents[1] is the folder `package://example-robot-data/...` paths resolve in."""
    try:
        dist = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed")
    return Path(dist.locate_file("cmeel.prefix/share/example-robot-data/robots"))


@pytest.fixture(scope="session")
def result() -> PlanResult:
    """The default synthetic result (10 intervals, walker3d; test/synthetic_result.py)."""
    return make_result()


@pytest.fixture(name="make_result", scope="session")
def make_result_fixture():
    """`make_result(**changes)`: a synthetic result with some fields replaced."""
    return make_result


@pytest.fixture
def start_ns() -> int:
    return START_NS
