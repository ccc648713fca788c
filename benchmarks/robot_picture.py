"""Each benchmarked robot at its mid-step node as rerun draws it: its own URDF's meshes
placed by the recording's /tf (`gait_planner.viz.rerun_robot` draws plans the same way),
photographed in rerun's web viewer by headless Chromium (`gait_planner.viz.rerun_screenshot`)
and set side by side in one PNG.

The mid-step node is the node nearest half the half cycle (t_(N-1) / 2). The URDF's
``package://`` paths are resolved in the example-robot-data wheel's share folder.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

__all__ = ["mid_step_picture"]

SIZE = (700, 800)  # px per robot


def _pose_rrd(mcap: str, rrd: Path, package_root: Path) -> str:
    """A one-pose .rrd of the recording at its mid-step node; its caption."""
    import rerun as rr
    import rerun.blueprint as rrb

    from gait_planner.io.mcap_reader import read_plan_mcap
    from gait_planner.viz.rerun_draw import log_ground
    from gait_planner.viz.rerun_robot import log_transform, log_urdf

    rec = read_plan_mcap(mcap)
    n = int(np.argmin(np.abs(rec.times - rec.times[-2] / 2)))
    base = next(t for t in rec.tf[n] if t.parent == "world").translation
    height = float(base[2])  # the camera: front-left, a robot's height away per metre
    eye = rrb.EyeControls3D(position=base + height * np.array([1.2, 2.4, 0.3]),
                            look_target=base * [1.0, 1.0, 0.6], eye_up=[0.0, 0.0, 1.0])
    stream = rr.RecordingStream("gait_planner_robot")
    stream.save(rrd)
    stream.send_blueprint(rrb.Blueprint(rrb.Spatial3DView(origin="/world", eye_controls=eye),
                                        collapse_panels=True))
    stream.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    log_ground(stream)
    log_urdf(stream, rec.urdf, "", [str(package_root)], "robot")
    for t in rec.tf[n]:
        log_transform(stream, t.parent, t.child, t.translation, t.rotation, static=True)
    stream.flush()
    stream.disconnect()
    return f"node {n} of {len(rec.times) - 1} ({rec.phases[n]})"


def mid_step_picture(recordings: dict[str, str], path: Path, package_root: Path) -> Path:
    """robot -> recording: one PNG with each robot at mid-step, captioned (module docstring)."""
    from PIL import Image, ImageDraw

    from gait_planner.viz.rerun_screenshot import screenshot_rrd

    pictures = []
    with tempfile.TemporaryDirectory() as tmp:
        for robot, mcap in recordings.items():
            rrd, png = Path(tmp) / f"{robot}.rrd", Path(tmp) / f"{robot}.png"
            caption = _pose_rrd(mcap, rrd, package_root)
            screenshot_rrd(rrd, png, width=SIZE[0], height=SIZE[1])
            image = Image.open(png).convert("RGB")
            ImageDraw.Draw(image).text((12, 70), f"{robot}: {caption}", fill=(0, 0, 0))
            pictures.append(image)
    sheet = Image.new("RGB", (SIZE[0] * len(pictures), SIZE[1]), "white")
    for i, image in enumerate(pictures):
        sheet.paste(image, (SIZE[0] * i, 0))
    path.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(path)
    return path
