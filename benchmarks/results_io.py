"""Writing benchmark results: `benchmarks/results/<name>.json` with a header saying where
and when they were measured (machine, date, commit, versions), shared by the scripts."""

from __future__ import annotations

import datetime
import json
import os
import platform
import subprocess
from pathlib import Path

import casadi
import numpy as np

HERE = Path(__file__).resolve().parent
# $GAIT_PLANNER_BENCH_RESULTS: another folder for the JSON and the figures (bench-quick's
# smoke runs), so that they never overwrite the report's results
OTHER = os.environ.get("GAIT_PLANNER_BENCH_RESULTS")
RESULTS = Path(OTHER) if OTHER else HERE / "results"


def figure_path(name: str) -> Path:
    """Where a figure goes: benchmarks/<name> next to REPORT.md, or the other folder."""
    return RESULTS / name if OTHER else HERE / name


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _commit() -> str:
    """HEAD's hash, with "+dirty" when tracked files differ from it ("unknown" outside git)."""
    root = Path(__file__).resolve().parent.parent
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=root, capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               cwd=root, capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+dirty" if dirty.strip() else "")


def header() -> dict:
    """Machine (CPU model, cores, load at the start), UTC date, git commit and versions."""
    return {
        "date_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "commit": _commit(),
        "cpu": _cpu_model(),
        "cores": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0],
        "platform": platform.platform(),
        "python": platform.python_version(),
        "casadi": casadi.__version__,
        "numpy": np.__version__,
    }


def _plain(value):
    """numpy scalars and arrays as JSON numbers and lists."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def write_results(name: str, rows: list[dict], meta: dict | None = None) -> Path:
    """Write {"header": header() + meta, "rows": rows} to benchmarks/results/<name>.json."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{name}.json"
    document = {"header": {**header(), **(meta or {})}, "rows": rows}
    path.write_text(json.dumps(document, indent=1, default=_plain) + "\n")
    return path


def load_results(name: str) -> dict | None:
    """benchmarks/results/<name>.json as written by `write_results`, or None if absent."""
    path = RESULTS / f"{name}.json"
    return json.loads(path.read_text()) if path.exists() else None
