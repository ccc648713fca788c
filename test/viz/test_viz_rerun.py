"""The rerun view: a saved .rrd is complete, loadable and holds the expected entities."""

from __future__ import annotations

import dataclasses
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

rr = pytest.importorskip("rerun")

from gait_planner.viz.rerun_view import log_plan, save_rrd, show  # noqa: E402

RERUN = Path(sys.executable).with_name("rerun")


def _rerun_cli() -> str | None:
    return str(RERUN) if RERUN.is_file() else shutil.which("rerun")


@pytest.fixture(scope="module")
def rrd(result, tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("rrd") / "plan.rrd"
    assert save_rrd(result, path) == path.resolve()
    return path


def test_saved_rrd_is_non_empty_and_alone(rrd):
    assert rrd.stat().st_size > 10_000
    assert sorted(p.name for p in rrd.parent.iterdir()) == ["plan.rrd"]  # no temporary file


@pytest.mark.skipif(_rerun_cli() is None, reason="the rerun CLI (rerun-sdk) is not installed")
def test_rrd_verify_and_entities(rrd, result):
    done = subprocess.run([_rerun_cli(), "rrd", "verify", str(rrd)], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    stats = subprocess.run([_rerun_cli(), "rrd", "stats", str(rrd)], capture_output=True,
                           text=True, timeout=120)
    assert stats.returncode == 0, stats.stderr
    for entity in ("/world/walker/torso", "/world/walker/foot_l", "/world/contacts/forces",
                   "/world/skeleton", "/plots/joint_angle/knee_r",
                   "/plots/joint_torque/hip_l_yaw", "/plots/contact_force/foot_r_heel/z",
                   "/plots/energy/total", "/plan",
                   "/world/trails/com", "/world/trails/foot_l_forefoot", "/world/com_total",
                   "/world/contacts/wrenches", "/world/contacts/centers_of_pressure",
                   "/plots/angular_momentum/y", "/plots/roll_moment/foot_l",
                   "/plots/phase_boundaries/energy", "/plots/phase_boundaries/joint_angle_hip_left",
                   "/phase"):
        assert entity in stats.stdout, entity


def _node_values(rrd: Path, entity: str, component: str) -> dict[int, list]:
    """{node: value} of one temporal component of a saved recording, read back through
    rerun's own chunk reader."""
    from rerun.chunk import RrdReader

    out = {}
    for chunk in RrdReader(rrd).stream():
        if chunk.entity_path != entity or chunk.is_static:
            continue
        batch = chunk.to_record_batch()
        column = next(n for n in batch.schema.names if n.endswith(component))
        for row in batch.select(["node", column]).to_pylist():
            out[row["node"]] = row[column]
    return out


def test_every_node_holds_its_contact_forces_and_skeleton(rrd, result):
    """Read back: at every node the force arrows are the active contacts' ground forces
    (FORCE_SCALE m per N), labelled with their names and magnitudes, and the skeleton has
    the same strips at every node (columnar chunks, one row per node)."""
    from gait_planner.viz.rerun_view import FORCE_SCALE

    vectors = _node_values(rrd, "/world/contacts/forces", "Arrows3D:vectors")
    labels = _node_values(rrd, "/world/contacts/forces", "Arrows3D:labels")
    strips = _node_values(rrd, "/world/skeleton", "LineStrips3D:strips")
    assert sorted(vectors) == sorted(strips) == list(range(result.n_nodes))
    for n in range(result.n_nodes):
        names = list(result.active_contacts[n])
        expected = [np.asarray(result.contact_forces[c], dtype=float)[n] for c in names]
        assert np.allclose(np.array(vectors[n]).reshape(-1, 3),
                           np.array(expected).reshape(-1, 3) * FORCE_SCALE, rtol=1e-6,
                           atol=1e-6)
        assert [label.split(":")[0] for label in labels[n]] == names
        assert len(strips[n]) == len(strips[0])


def test_failed_save_leaves_nothing(result, tmp_path, monkeypatch):
    import gait_planner.viz.rerun_view as view

    def fail(*_args):
        raise RuntimeError("logging failed")

    monkeypatch.setattr(view, "_log_series", fail)
    with pytest.raises(RuntimeError, match="logging failed"):
        save_rrd(result, tmp_path / "plan.rrd")
    assert list(tmp_path.iterdir()) == []


def test_log_plan_into_a_memory_recording(result):
    rec = rr.RecordingStream("gait_planner_test")
    memory = rec.memory_recording()
    log_plan(result, rec)
    rec.flush()
    assert len(memory.drain_as_bytes()) > 10_000


def test_log_plan_with_a_node_without_contacts(result, make_result):
    active = (result.active_contacts[0], ()) + result.active_contacts[2:]
    rec = rr.RecordingStream("gait_planner_test")
    memory = rec.memory_recording()
    log_plan(make_result(active_contacts=active), rec)
    rec.flush()
    assert len(memory.drain_as_bytes()) > 0


def test_show_without_display_says_what_to_do(result, monkeypatch):
    if not sys.platform.startswith("linux"):
        pytest.skip("the display check applies to Linux")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(RuntimeError, match="save_rrd"):
        show(result)


# ---------------------------------------------------------------- what the view adds (#11)

import rerun.blueprint as rrb  # noqa: E402

from gait_planner.viz.rerun_blueprint import blueprint  # noqa: E402
from gait_planner.viz.rerun_series import (BOUNDARY_COLOR, COLOUR_KEY,  # noqa: E402
                                          angular_momentum, phase_boundaries, plot_groups,
                                          series_color, series_values)


def _rigid_motion(result, omega: float, velocity) -> np.ndarray:
    """q of `result`'s first pose turned about the vertical through its centre of mass at
    `omega` rad/s and moved at `velocity` m/s, at `result.times`."""
    scene = result.scene
    q0 = np.asarray(result.q[0], dtype=float).reshape(-1, 12)
    masses = np.array([b.mass for b in scene.bodies])
    c = masses @ q0[:, :3] / masses.sum()
    rows = []
    for t in result.times:
        a = omega * t
        R = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0, 0, 1.0]])
        phi = c + (q0[:, :3] - c) @ R.T + np.asarray(velocity) * t
        directors = q0[:, 3:].reshape(-1, 3, 3) @ R.T
        rows.append(np.concatenate([phi, directors.reshape(-1, 9)], axis=1).ravel())
    return np.array(rows)


def test_angular_momentum_of_a_rigid_turn_is_inertia_times_rate(make_result):
    """Turning the whole body as one rigid body about the vertical through its centre of
    mass at omega: L(t) = R(t) I_c R(t)^T (0, 0, omega), I_c the inertia tensor about the
    centre of mass (principal inertias along the directors plus parallel axes), up to the
    time discretisation, O((omega h)^2) = 1e-4; moving the body as well adds nothing."""
    result = make_result()
    omega, velocity = 0.8, [1.2, -0.3, 0.1]
    turn = dataclasses.replace(result, q=_rigid_motion(result, omega, velocity))
    q0 = np.asarray(result.q[0], dtype=float).reshape(-1, 12)
    masses = np.array([b.mass for b in result.scene.bodies])
    c = masses @ q0[:, :3] / masses.sum()
    I_c = np.zeros((3, 3))
    for m, row, body in zip(masses, q0, result.scene.bodies):
        r, D = row[:3] - c, row[3:].reshape(3, 3).T  # D = [d1 d2 d3]
        I_c += m * (r @ r * np.eye(3) - np.outer(r, r)) + D @ np.diag(body.inertia) @ D.T

    def L_exact(t: float) -> np.ndarray:
        a = omega * t
        R = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0, 0, 1.0]])
        return R @ I_c @ R.T @ [0.0, 0.0, omega]

    t = np.asarray(result.times)
    # an interval's value belongs to its middle; inner nodes average two intervals, the end
    # nodes hold their one interval's value
    middles = 0.5 * (t[:-1] + t[1:])
    times = [middles[0], *(0.5 * (middles[:-1] + middles[1:])), middles[-1]]
    expected = np.array([L_exact(tn) for tn in times])
    L = angular_momentum(turn)
    assert np.abs(expected[:, 2]).min() > 0.5  # kg m^2/s (I_zz ~ 1.1 kg m^2): a real test
    np.testing.assert_allclose(L, expected, atol=1e-4 * np.abs(expected).max())
    still = dataclasses.replace(result, q=_rigid_motion(result, 0.0, velocity))
    np.testing.assert_allclose(angular_momentum(still), 0.0, atol=1e-9)


def test_angular_momentum_is_the_discrete_momentum_about_the_centre_of_mass(result, model):
    """Per interval, L about the centre of mass equals the package's own angular momentum
    about the origin (`DiscreteMechanics.angular_momentum`) of q_mid = (q_n + q_n+1) / 2 and
    p = M (q_n+1 - q_n) / h_n, less c x P; intervals average to nodes."""
    mech = model("walker3d").mech
    q = np.asarray(result.q, dtype=float)
    h = np.diff(result.times)
    masses = np.array([b.mass for b in result.scene.bodies])
    M = mech.mb.mass_diagonal
    per_interval = []
    for n in range(len(h)):
        mid, p = 0.5 * (q[n] + q[n + 1]), M * (q[n + 1] - q[n]) / h[n]
        c = masses @ mid.reshape(-1, 12)[:, :3] / masses.sum()
        P = np.array(mech.linear_momentum(p)).ravel()
        per_interval.append(np.array(mech.angular_momentum(mid, p)).ravel() - np.cross(c, P))
    per_interval = np.array(per_interval)
    expected = np.concatenate([per_interval[:1], 0.5 * (per_interval[:-1] + per_interval[1:]),
                               per_interval[-1:]])
    np.testing.assert_allclose(angular_momentum(result), expected, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("scene", ["compass", "walker2d", "walker3d"])
def test_plot_groups_hold_every_series_once(make_result, scene):
    result = make_result(scene)
    groups = plot_groups(result)
    paths = [p for g in groups for p in g.paths]
    assert sorted(paths) == sorted(series_values(result))  # each logged series, once
    keys = [g.key for g in groups]
    assert len(set(keys)) == len(keys)
    names = result.joint_angle_names
    if scene == "compass":
        assert keys[:2] == ["joint_angle_hip_joints", "joint_torque_hip_joints"]
    else:  # one joint of one leg per plot: hip_r_pitch, hip_r_roll, hip_r_yaw; knee_r
        hip = next(g for g in groups if g.key == "joint_angle_hip_right")
        knee = next(g for g in groups if g.key == "joint_torque_knee_left")
        assert hip.paths == tuple(f"plots/joint_angle/{a}" for a in names
                                  if re.fullmatch("hip_r(_(pitch|roll|yaw))?", a))
        assert len(hip.paths) == (3 if scene == "walker3d" else 1)
        assert knee.paths == ("plots/joint_torque/knee_l",)
        assert (hip.title, knee.title) == ("hip R (deg)", "knee L (N m)")
    bodies = {c.body for c in result.scene.contacts}
    assert {k for k in keys if k.startswith("contact_force_")} == {
        f"contact_force_{b}" for b in bodies}
    assert ("roll_moment" in keys) == (scene == "walker3d")
    blueprint(result)  # builds for every scene


def _views(container):
    for item in getattr(container, "contents", []):
        if isinstance(item, rrb.TimeSeriesView):
            yield item
        else:
            yield from _views(item)


def test_no_plot_legend_covers_the_lines(make_result):
    """rerun 0.41 draws a legend inside its plot: every plot hides it; a plot's series are
    told apart by colours said in its title or in the colour key of the solve summary, and
    the joint plots share pitch, roll, yaw colours."""
    result = make_result("walker3d")
    views = list(_views(blueprint(result).root_container))
    assert len(views) == len(plot_groups(result))
    for view in views:
        legend = view.properties["PlotLegend"]
        assert legend.visible.as_arrow_array().to_pylist() == [False], view.name
    colour = {p.split("/")[-1]: series_color(result, p) for g in plot_groups(result)
              for p in g.paths if p.startswith("plots/joint_angle/")}
    for axis in ("pitch", "roll", "yaw"):
        assert colour[f"hip_r_{axis}"] == colour[f"ankle_l_{axis}"], axis
    assert len({colour["hip_r_pitch"], colour["hip_r_roll"], colour["hip_r_yaw"]}) == 3
    for group in plot_groups(result):
        if len(group.paths) > 1 and not group.key.startswith("joint_"):
            colours = group.title.partition(": ")[2]  # the colours of its series
            assert " red" in colours or " blue" in colours, group.title
    for words in ("pitch blue", "roll orange", "yaw green", "x red", "phase boundaries"):
        assert words in COLOUR_KEY


def test_phase_boundaries_are_the_phase_starts_and_the_half_cycle_end(result):
    t = result.times - result.times[0]
    starts = [t[n] for n in range(1, result.n_nodes) if result.phases[n] != result.phases[n - 1]]
    assert len(starts) == len(result.scene.gait.phases) - 1
    np.testing.assert_allclose(phase_boundaries(result), starts + [result.duration])


def test_series_values_in_the_units_of_their_titles(result):
    values = series_values(result)
    np.testing.assert_allclose(values["plots/joint_angle/knee_r"],
                               np.degrees(result.joint_angles[:, list(
                                   result.joint_angle_names).index("knee_r")]))
    V = result.potential_energy - result.potential_energy[0]
    np.testing.assert_allclose(values["plots/energy/potential"], V)
    np.testing.assert_allclose(values["plots/energy/total"], result.kinetic_energy + V)
    np.testing.assert_allclose(values["plots/roll_moment/foot_r"], result.roll_moments["foot_r"])


@pytest.mark.skipif(_rerun_cli() is None, reason="the rerun CLI (rerun-sdk) is not installed")
def test_blueprint_is_saved_in_the_rrd(rrd, result):
    """The .rrd holds a blueprint store, made active and default, with the views of the
    layout: `rerun rrd print -vvv` shows its stores and the views' names."""
    done = subprocess.run([_rerun_cli(), "rrd", "print", "-vvv", str(rrd)], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    text = done.stdout
    assert "Blueprint," in text and "Recording," in text  # the two stores' ids
    for name in ("walker", "phases", "solve summary",
                 *(g.title for g in plot_groups(result))):
        assert f"[{name}]" in text, name  # ViewBlueprint:display_name
    for kind in ("3D", "TimeSeries", "TextDocument", "StateTimeline"):
        assert f"[{kind}]" in text, kind  # ViewBlueprint:class_identifier
    assert "TimePanelBlueprint:state" in text and "ViewportBlueprint:root_container" in text


# ------------------------------------------------ the view as a person sees it (Chromium)

from gait_planner.viz.rerun_screenshot import chromium, rerun_cli, screenshot_rrd  # noqa: E402


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_screenshot_of_the_web_viewer(rrd, tmp_path):
    """rerun's web viewer in headless Chromium (software WebGL) shows the saved layout:
    a page of many colours (not blank, not the loading screen), the walker's red right and
    blue left bodies and trails in the large 3D view at the top left, and the grey phase
    boundaries as vertical lines through the plots on the right. About 25 s."""
    if chromium() is None:
        pytest.skip("no Chromium (Debian: apt-get install chromium) for the screenshot test")
    if rerun_cli() is None:
        pytest.skip("the rerun CLI (rerun-sdk) is not installed")
    from PIL import Image

    png = screenshot_rrd(rrd, tmp_path / "view.png", width=1600, height=1000, timeout=180)
    with Image.open(png) as image:
        assert image.size == (1600, 1000)
        a = np.asarray(image.convert("RGB")).astype(int)
    where = f"(picture: {png})"
    assert len(np.unique(a.reshape(-1, 3), axis=0)) > 3000, where  # a blank page has 1

    def reddish(x):
        return int((x[..., 0] - np.maximum(x[..., 1], x[..., 2]) > 40).sum())

    def bluish(x):
        return int((x[..., 2] - np.maximum(x[..., 0], x[..., 1]) > 40).sum())

    view3d = a[50:500, :620]  # the 3D view: left 40 % of the width, top half
    assert reddish(view3d) > 1000 and bluish(view3d) > 1000, where
    plots = a[40:950, 740:]  # the time series: right half
    grey = np.abs(plots - np.array(BOUNDARY_COLOR)).max(axis=2) <= 12
    assert (grey.sum(axis=0) >= 40).sum() >= 4, where  # vertical phase-boundary lines
