"""The figure of a recording: drawn from the MCAP alone, written atomically, and the
`gait-planner report` command around it (figure + independent check, clear errors)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest

from gait_planner.cli import main
from gait_planner.io.mcap_writer import write_plan_mcap
from gait_planner.io.plots import plot_recording


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
