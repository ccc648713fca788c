"""Plan walker3d's gait up a 5 degree ramp through the Python API, check it with the
independent verifier, record it and print its summary:

    .venv/bin/python examples/plan_a_gait.py [OUTPUT_FOLDER]

(replay the recording with `.venv/bin/rerun OUTPUT_FOLDER/ramp.mcap`, or ros2 bag play).
"""

import json
import sys
from pathlib import Path

from gait_planner import PlanRequest, RequestError, check, plan, record, summary

folder = Path(sys.argv[1] if len(sys.argv) > 1 else "runs")
try:
    result = plan(PlanRequest("walker3d", slope=5.0, compiled=True))
except RequestError as err:  # a request the scene cannot plan: the sentence says why
    sys.exit(f"refused: {err}")
if not result.success:
    sys.exit(f"no plan: {result.message}")
report = check(result)
print(report.summary())
mcap = record(result, folder / "ramp.mcap")
print(json.dumps(summary(result), indent=1))
print(f"recorded {mcap}")
sys.exit(0 if report.ok else 1)
