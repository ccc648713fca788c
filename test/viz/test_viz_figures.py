"""The figure of a recording: drawn from the MCAP alone, written atomically, and the
`gait-planner report` command around it (figure + independent check, clear errors)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest

from gait_planner.cli import main
from gait_planner.io.mcap_writer import write_plan_mcap
from gait_planner.viz.figures import plot_recording


@pytest.fixture(scope="module")
def recording(result, tmp_path_factory) -> Path:
    return write_plan_mcap(result, tmp_path_factory.mktemp("plot") / "plan.mcap")


def test_figure_is_a_picture_with_content(recording, tmp_path):
    png = plot_recording(recording, tmp_path / "plan.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.png"]  # no temporary file
    image = mpimg.imread(png)
    assert image.shape[0] > 800 and image.shape[1] > 1000
    # not a blank page: many distinct colours (lines of every panel)
    colours = np.unique((image[..., :3] * 255).astype(np.uint8).reshape(-1, 3), axis=0)
    assert len(colours) > 200


def test_report_command_draws_and_checks(recording, tmp_path, capsys):
    png = tmp_path / "figure.png"
    code = main(["report", str(recording), "--png", str(png)])
    out = capsys.readouterr().out
    assert png.is_file() and f"figure: {png}" in out
    # the synthetic plan of the io tests is not an optimum of the planner: the verifier
    # reads it and reports, and the exit code says whether every check passed
    assert ("all checks passed" in out) == (code == 0)


def test_report_refuses_what_is_not_a_recording(tmp_path, capsys):
    assert main(["report", str(tmp_path / "missing.mcap")]) == 2
    assert "is not an existing .mcap file" in capsys.readouterr().err


# ------------------------------------------------ what a person reads: the figure's layout


def _legends(fig) -> list:
    """Every legend of `fig`: of its axes, of the figure and of its subfigures."""
    out = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    stack = [fig]
    while stack:
        f = stack.pop()
        out += list(f.legends)
        stack += list(f.subfigs)
    return out


def _data_pixels(ax, line) -> np.ndarray:
    """(m, 2) display points along `line` (its segments subdivided), within the axes."""
    xy = line.get_transform().transform(np.asarray(line.get_xydata(), dtype=float))
    xy = xy[np.isfinite(xy).all(axis=1)]
    if len(xy) > 1:
        s = np.linspace(0.0, 1.0, 12)[:, None, None]
        xy = (xy[:-1] + s * (xy[1:] - xy[:-1])).reshape(-1, 2)
    box = ax.bbox
    inside = ((xy[:, 0] > box.x0) & (xy[:, 0] < box.x1) & (xy[:, 1] > box.y0)
              & (xy[:, 1] < box.y1))
    return xy[inside]


@pytest.fixture(scope="module")
def figure(recording):
    import matplotlib.pyplot as plt

    from gait_planner.io.mcap_reader import read_plan_mcap
    from gait_planner.viz.figures import recording_figure

    rec = read_plan_mcap(recording)
    fig = recording_figure(rec)
    fig.canvas.draw()
    yield rec, fig
    plt.close(fig)


def test_no_legend_covers_a_line(figure):
    """Legends sit outside the axes: no point of any plotted line (data, limits, contact
    switches) lies under a legend."""
    _, fig = figure
    renderer = fig.canvas.get_renderer()
    boxes = [legend.get_window_extent(renderer).padded(-1.0) for legend in _legends(fig)]
    assert len(boxes) >= 4  # schedule, forces, energies, certificate (and the joint key)
    for ax in fig.axes:
        for line in ax.lines:
            points = _data_pixels(ax, line)
            for box in boxes:
                covered = ((points[:, 0] > box.x0) & (points[:, 0] < box.x1)
                           & (points[:, 1] > box.y0) & (points[:, 1] < box.y1))
                assert not np.any(covered), (ax.get_title(), line.get_label())


def test_joint_panels_hold_one_joint_of_one_leg(figure):
    """One panel per joint, side and quantity, at most three lines (pitch, roll, yaw) in
    the key's colours; the phases are named in the schedule's legend with their time step."""
    rec, fig = figure
    joint_axes = [ax for ax in fig.axes if " angle" in ax.get_title() or " torque" in
                  ax.get_title()]
    # walker3d: hip, knee, ankle x right, left x angle, torque
    assert len(joint_axes) == 12
    titles = {ax.get_title() for ax in joint_axes}
    assert {"hip angle, right", "knee torque, left", "ankle angle, left"} <= titles
    for ax in joint_axes:
        assert 1 <= len(ax.lines) <= 3, ax.get_title()
    assert max(len(ax.lines) for ax in fig.axes if ax.get_title().startswith("ground force")) <= 4
    texts = [t.get_text() for legend in _legends(fig) for t in legend.get_texts()]
    assert {"pitch", "roll", "yaw"} <= set(texts)
    for phase in set(rec.phases):
        named = [t for t in texts if t.startswith(f"{phase}: ")]
        assert len(named) == 1 and " h " in named[0] and "ms" in named[0], (phase, texts)


# ------------------------------------------------ what a person reads: the report's text


def test_report_text_is_grouped_with_units_limits_and_a_verdict(recording):
    """Each line once; every judged line carries a unit and its limit; the last line is
    the verdict, the verifier's."""
    from gait_planner.verify import verify_recording

    report = verify_recording(recording)
    lines = report.summary().splitlines()
    assert len(lines) == len(set(lines)), [x for x in lines if lines.count(x) > 1]
    judged = [x for x in lines if x.startswith("  ") and x.rstrip().endswith((" ok", " FAILED"))]
    assert len(judged) >= 25
    units = ("m", "N", "N s", "N m", "s", "J s", "rel.", "%", "deg/s", "of peak")
    for line in judged:
        if line.split()[0] == "planner":
            continue
        assert "limit" in line or "no zigzag" in line, line
        value = line[2:].split("limit")[0] if "limit" in line else line
        assert any(f" {u} " in f"{value} " for u in units), line
    groups = [x for x in lines if not x.startswith(" ") and x.endswith(":")]
    assert {"contacts:", "time and cost:", "physical plausibility:"} <= set(groups)
    assert lines[-1].startswith("verdict: ")
    assert ("all checks passed" in lines[-1]) == report.ok
    assert report.summary().count("continuous dynamics (") == 1  # once, not twice


def test_report_marks_a_value_over_its_limit(recording):
    """A planted residual above its limit: its line says FAILED and the verdict too."""
    import dataclasses

    from gait_planner.verify import verify_recording
    from gait_planner.verify.limits import LIMITS

    report = dataclasses.replace(
        verify_recording(recording), max_dynamics_residual=100 * LIMITS["dynamics"],
        failures=("the discrete Euler-Lagrange equation of node 3 has a relative residual",))
    lines = report.summary().splitlines()
    line = next(x for x in lines if "residual, relative" in x)
    assert line.endswith("FAILED") and "1e-06 rel." in line and "limit 1e-08 rel." in line
    assert lines[-1] == "verdict: 1 check(s) FAILED (listed above)"
