"""The picture of the rerun view at the top of README.md (`make docs` retakes it): walker3d's plan in rerun's web viewer.

Usage: .venv/bin/python benchmarks/rerun_view.py [--rrd FILE] [--out benchmarks/rerun_view.png]
                                                 [--time 0.4]

Without --rrd it plans walker3d's default request (compiled derivatives, ~10 s once they
are cached) and saves the .rrd in a temporary folder. The recording is shown in rerun's web
viewer in headless Chromium (`gait_planner.viz.rerun_screenshot`, 1600 x 1000), the time
cursor is moved to --time (s) and the page is saved as --out.

Moving the time cursor clicks the viewer's pause button and drags the cursor along the
collapsed time panel at the bottom of the page: the pixel positions below were read off
rerun 0.41's web viewer at 1600 x 1000 for walker3d's default plan (time 0 at x = 267,
the last node, 0.60 s, at x = 1393); another rerun version or plan may need others.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from gait_planner.viz.rerun_screenshot import screenshot_rrd

PAUSE = (26, 985)  # the play/pause button of the collapsed time panel
BAR_Y, BAR_T0, BAR_END = 985, 267, 1393  # the time bar: y, x at t = 0, x of the last node


def _plan_rrd(folder: Path) -> Path:
    from gait_planner.viz.rerun_view import save_rrd
    from gait_planner.model.loader import load_scene
    from gait_planner.ocp.settings import settings_for
    from gait_planner.ocp.solve import Planner
    from gait_planner.strategies import plan_once

    scene = load_scene("walker3d")
    result = plan_once(Planner(), scene, settings_for(scene, compiled=True))
    if not result.success:
        raise SystemExit(f"walker3d did not plan: {result.message}")
    return save_rrd(result, folder / "walker3d.rrd")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rrd", type=Path, help="a recording (default: plan walker3d)")
    parser.add_argument("--out", type=Path, default=Path(__file__).with_name("rerun_view.png"))
    parser.add_argument("--time", type=float, default=0.4,
                        help="s, where the time cursor is put (walker3d: 0.60 s at the end)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        rrd = args.rrd or _plan_rrd(Path(folder))
        x = round(BAR_T0 + (BAR_END - BAR_T0) * args.time / 0.60)
        drag = [(BAR_END, BAR_Y), (BAR_END - 50, BAR_Y), ((BAR_END + x) // 2, BAR_Y), (x, BAR_Y)]
        print(screenshot_rrd(rrd, args.out, gestures=[[PAUSE], drag]))


if __name__ == "__main__":
    main()
