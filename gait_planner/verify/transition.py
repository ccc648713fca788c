"""Checks of a recording that begins with a transition (metadata ``transition_nodes`` = N,
`gait_planner.ocp.transition`): a motion from a given start state whose nodes 0 .. N-1 are
the transition's and whose nodes from N-1 on are the periodic gait, ``steps`` half cycles
joined by the mirror.

The transition's nodes 0 .. N (node N the gait's next) get every check of a plan of their
own (the discrete equations at nodes 1 .. N-1, contacts, cones, actuation, J and
duration); their periodicity is none, so the checks that pair nodes N-1, N with 0, 1 are
noted, not run. Node N-1 joins the two parts: it carries the transition's efforts and
contact forces (its discrete equation spans the transition's last interval and the gait's
first), so the gait's half cycle after it is not the gait's own at that node. The first
later half cycle in the gait's own orientation (``transition_half_cycles`` K: walk_on's
half cycle K + 1 or K + 2, whichever is even; odd for a motion mirrored, a start on the
other foot) is the gait itself, and gets every check of a (joined) plan, its periodic
continuation included, against the gait's J and duration (metadata ``gait_cost_value``,
``gait_duration``); with too few steps for one, the notes say so. The physical checks
and the continuous-dynamics certificate run on the whole motion.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from gait_planner.verify.joined import half_cycle, node_fields
from gait_planner.verify.physical import check_physical
from gait_planner.verify.recorded import certificate_of_recording
from gait_planner.verify.mechanics import parse_scene


def from_node(rec, first: int):
    """The recording from node `first` on, as a plan of its own: nodes renumbered from 0,
    times from 0, metadata without the transition's keys, and its first node's discrete force
    that of its first interval (a plan's node 0 carries f-_0 only; in the whole motion
    that node is inner and carries both intervals')."""
    changes = node_fields(rec, slice(first, None))
    t = np.asarray(rec.times, dtype=float)
    changes["nodes"] = np.arange(rec.n_nodes - first)
    changes["times"] = t[first:] - t[first]
    meta = {k: v for k, v in rec.metadata.items() if not k.startswith("transition_")}
    changes["metadata"] = meta
    gen = np.array(rec.generalized_force[first:], dtype=float)
    gen[0] *= (t[first + 1] - t[first]) / (t[first + 1] - t[first - 1])
    changes["generalized_force"] = gen
    return dataclasses.replace(rec, **changes)


def verify_transition(rec, verify_plan):
    """Check a recording that begins with a transition (module docstring); `verify_plan`
    checks the transition's nodes as a plan of their own (its metadata's periodicity is
    none: the checks that pair nodes N-1, N with 0, 1 are noted, not run) and the gait's
    part."""
    N, steps = int(rec.metadata["transition_nodes"]), int(rec.metadata["steps"])
    H, K = int(rec.metadata["half_cycle_nodes"]), int(rec.metadata["transition_half_cycles"])
    # the gait's first half cycle after the join whose contacts are the gait's own (not
    # mirrored: an even index of `ocp.walk_on`; odd if the whole motion is mirrored, a start
    # on the other foot), if the recording has one
    parity = 1 if rec.metadata.get("transition_mirrored") == "true" else 0
    own = K + 1 + (K + 1 + parity) % 2
    judged = own < K + steps
    first = N - 1 + (own - K) * (H - 2) if judged else N - 1
    tail = from_node(rec, first)
    # a join node is recorded with the earlier half cycle's phase name (`ocp.walk_on`); as
    # the first node of the gait's part it is in the gait's first phase, as its node 1
    tail = dataclasses.replace(tail, phases=(tail.phases[1],) + tuple(tail.phases[1:]))
    # the gait's part is judged against the gait's J (the transition's is the metadata's)
    gait = verify_plan(dataclasses.replace(tail, metadata=dict(
        tail.metadata, steps=str(max(K + steps - own, 1)),
        cost_value=rec.metadata["gait_cost_value"], duration=rec.metadata["gait_duration"])))
    own = verify_plan(dataclasses.replace(  # not "transition_nodes": checked as a plan
        (half := half_cycle(rec, N + 1)),
        metadata={k: v for k, v in half.metadata.items() if k != "transition_nodes"}))
    scene = parse_scene(rec.scene_text)
    physical = check_physical(rec, scene, float(rec.metadata["friction_coefficient"]))
    continuous = certificate_of_recording(rec)
    failures = [f for f in own.failures if f not in own.physical.failures
                and not f.startswith("continuous dynamics:")]
    failures += [f"the gait after the transition: {f}" for f in gait.failures
                 if judged and f not in gait.physical.failures
                 and not f.startswith("continuous dynamics:")]
    failures += list(physical.failures)
    failures += [f"continuous dynamics: {f}" for f in continuous.failures]
    gait_part = (f"every check of a plan ran on the gait from node {first}, " if judged else
                 "the gait's periodic checks need a half cycle of the gait's own orientation "
                 "after the join (not judged); ")
    notes = list(own.notes) + [
        f"{rec.metadata.get('initial_guess', 'a transition')} ({N} nodes) onto the gait: "
        + gait_part
        + f"the physical and continuous checks on all {rec.n_nodes} nodes"]
    return dataclasses.replace(own, path=str(rec.path), n_nodes=rec.n_nodes,
                               failures=tuple(failures), notes=tuple(notes),
                               physical=physical, continuous=continuous)
