"""``gait-planner library build|list|show|export``: gait libraries (`gait_planner.gaitlib`)."""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import sys
from pathlib import Path

from gait_planner.cli.errors import CliError
from gait_planner.gaitlib.grid import AXES

GRID_HELP = ("grid axes, comma-separated: field=start:stop:step or field=v1/v2/...; fields: "
             f"{', '.join(AXES)} (e.g. step_length=0.4:0.9:0.05,friction_coefficient=0.4:1.0:0.2)")


def add_library_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "library", help="build and inspect gait libraries: a grid of plans on Ray",
        description="A gait library is a folder of plans over a grid of requests, built on "
        "Ray by continuation (each point warm-started from a finished neighbour), with an "
        "SQLite index. Killing a build loses no finished plan; building again resumes.")
    commands = parser.add_subparsers(dest="library_command", metavar="COMMAND", required=True)
    build = commands.add_parser("build", help="plan every point of a grid into a folder")
    build.add_argument("--scene", required=True, help="a scene name or file")
    build.add_argument("--gait", default="", help="one of the scene's gaits (default: walk)")
    build.add_argument("--grid", required=True, help=GRID_HELP)
    build.add_argument("--out", required=True, metavar="FOLDER", help="the library's folder")
    build.add_argument("--intervals-per-phase", type=int, default=None, metavar="N",
                       help="grid of every plan (default: the scene's)")
    build.add_argument("--max-solve-time", type=float, default=None, metavar="S",
                       help="time limit of each point's plan")
    build.add_argument("--workers", type=int, default=None, metavar="N",
                       help="local Ray worker processes (default: one per core)")
    build.add_argument("--address", default=None,
                       help="an existing Ray cluster's address (ray start ...) instead")
    build.add_argument("--seeds", type=int, default=None, metavar="K",
                       help="points planned cold to start from (default: one per worker)")
    build.add_argument("--independent", action="store_true",
                       help="plan every point cold and on its own, without continuation")
    build.set_defaults(handler=_build)
    for name, text in (("list", "one line per finished point"),
                       ("show", "every field of one point")):
        sub = commands.add_parser(name, help=text)
        sub.add_argument("folder", metavar="FOLDER")
        if name == "show":
            sub.add_argument("point", metavar="NAME", help="a point's name (see list)")
        sub.set_defaults(handler=_list if name == "list" else _show)
    export = commands.add_parser("export", help="the index as CSV or JSON")
    export.add_argument("folder", metavar="FOLDER")
    export.add_argument("--format", choices=("csv", "json"), default="csv")
    export.set_defaults(handler=_export)


def _open(folder: str):
    from gait_planner.gaitlib.index import LibraryError, LibraryIndex, read_manifest

    path = Path(folder)
    try:
        manifest = read_manifest(path)
    except LibraryError as err:
        raise CliError(str(err)) from None
    index = LibraryIndex(path)
    try:
        return manifest, index.rows()
    finally:
        index.close()


def _build(args: argparse.Namespace) -> int:
    from gait_planner.gaitlib.build import build_library
    from gait_planner.gaitlib.grid import GridError, parse_grid
    from gait_planner.gaitlib.index import LibraryError, Manifest
    from gait_planner.problem import resolve
    from gait_planner.request import RequestError
    from gait_planner.gaitlib.worker import point_request
    from gait_planner.model.loader import find_scene

    fixed = {k: v for k, v in (("intervals_per_phase", args.intervals_per_phase),
                               ("max_solve_time", args.max_solve_time)) if v is not None}
    try:
        grid = parse_grid(args.grid)
        manifest = Manifest(scene=args.scene, gait=args.gait, grid=grid.text(), request=fixed)
        for i in (grid.indices()[0], grid.indices()[-1]):  # refused before Ray starts
            resolve(point_request(manifest, grid.name(i), grid.values(i), cold=True),
                    find_scene)
        summary = build_library(args.out, manifest, workers=args.workers,
                                address=args.address, seeds=args.seeds,
                                continuation=not args.independent)
    except (GridError, LibraryError, RequestError) as err:
        raise CliError(str(err)) from None
    print(f"library {args.out}: {summary.planned} points planned ({summary.failed} failed), "
          f"{summary.skipped} finished before, {summary.total} in all; "
          f"{summary.iterations} IPOPT iterations in {summary.wall_time:.1f} s")
    return 0


def _list(args: argparse.Namespace) -> int:
    manifest, rows = _open(args.folder)
    print(f"# {manifest.scene} {manifest.gait or 'walk'}: {manifest.grid} "
          f"({len(rows)} points finished)")
    for row in rows:
        fields = " ".join(f"{k}={v:g}" for k, v in row.request.items())
        what = (f"J {row.cost:.4g}, {row.duration:.3f} s, {row.iterations} it, from "
                f"{row.start}, checks {row.checks if row.checks == 'pass' else 'FAIL'}"
                if row.status == "ok" else f"FAILED: {row.reason}")
        print(f"{row.name} {fields}: {what}")
    return 0


def _show(args: argparse.Namespace) -> int:
    _, rows = _open(args.folder)
    row = next((r for r in rows if r.name == args.point), None)
    if row is None:
        raise CliError(f"{args.folder} has no finished point {args.point!r} "
                       f"(see 'gait-planner library list {args.folder}')")
    print(json.dumps(dataclasses.asdict(row), indent=1))
    return 0


def _export(args: argparse.Namespace) -> int:
    _, rows = _open(args.folder)
    records = [dataclasses.asdict(r) for r in rows]
    if args.format == "json":
        print(json.dumps(records, indent=1))
        return 0
    axes = sorted({k for r in rows for k in r.request})
    columns = ["name"] + axes + [k for k in (records[0] if records else {})
                                 if k not in ("name", "request")]
    out = csv.DictWriter(sys.stdout, columns)
    out.writeheader()
    for record in records:
        out.writerow({**{k: v for k, v in record.items() if k != "request"},
                      **record["request"], "sigma": json.dumps(record["sigma"])})
    return 0
