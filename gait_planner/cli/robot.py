"""``gait-planner scene from-urdf``: a scene drafted from a robot's URDF
(`gait_planner.model.urdf_import`), and the ``--urdf`` option of ``plan`` that drafts and
plans in one step."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gait_planner.cli.errors import CliError
from gait_planner.model.urdf_collision import LEG_CLEARANCE
from gait_planner.model.urdf_mirror import MIRROR_COM_TOLERANCE, MIRROR_TOLERANCE

URDF_HELP = ("a robot's URDF: its legs are planned in its own joint names and limits, every "
             "other joint locked (gait-planner scene from-urdf --help)")


def add_urdf_options(parser: argparse.ArgumentParser) -> None:
    """The importer's options, shared by `scene from-urdf` and `plan --urdf`."""
    parser.add_argument("--feet", metavar="LEFT_LINK,RIGHT_LINK",
                        help="the two foot links (default: the two lowest leaves of the tree)")
    parser.add_argument("--lock", metavar="JOINT=RAD,...", default="",
                        help="angles of locked joints (default: the URDF's zero)")
    parser.add_argument("--package-dir", action="append", default=[], metavar="DIR",
                        help="a folder holding the packages of package:// mesh paths "
                        "(repeatable; the URDF's own folder and its parents are tried too)")
    parser.add_argument("--name", help="the scene's name (default: the URDF robot's name)")
    parser.add_argument("--mirror-tolerance", type=float, default=MIRROR_TOLERANCE,
                        metavar="FRACTION", help="a right leg link whose mass or inertia "
                        "differs from its left partner's mirror image by less than this "
                        "fraction is written as that mirror image, and the draft's header "
                        f"says so (default {MIRROR_TOLERANCE:g}); centres of mass: "
                        f"{MIRROR_COM_TOLERANCE * 100:g} cm")
    parser.add_argument("--leg-clearance", type=float, default=LEG_CLEARANCE, metavar="M",
                        help="the distance kept between the two legs' collision spheres "
                        "(the draft's leg_clearance gait option; default "
                        f"{LEG_CLEARANCE:g} m)")


def add_scene_parser(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser("scene", help="draft a scene from a robot's URDF")
    verbs = parser.add_subparsers(dest="verb", metavar="VERB")
    verbs.required = True
    draft = verbs.add_parser(
        "from-urdf", help="draft a scene from a URDF",
        description="Draft a scene for a robot's URDF: the two legs (floating base to feet) "
        "as bodies and revolute joints with the URDF's names, angle convention and limits "
        "(effort limits as hard torque bounds), every other joint locked and merged, "
        "contact points from the feet's collision geometry, the mirror map from the "
        "left/right names, a default gait scaled to the leg length. Refused with the joint "
        "or link named: a loop, a leg joint that is not revolute, a moving link without "
        "mass or with a non-physical inertia, no two feet, a foot without collision "
        "geometry, an unreadable mesh, a robot that is not left-right symmetric.")
    draft.add_argument("urdf", metavar="ROBOT.urdf")
    draft.add_argument("--out", help="the scene file to write (default: stdout)")
    add_urdf_options(draft)
    draft.set_defaults(handler=_from_urdf)


def draft_of(args: argparse.Namespace, folder: Path | None = None):
    """The `UrdfDraft` of args.urdf with the importer's options, to be written in `folder`
    (its ``robot:`` section names the URDF and --package-dir folders relative to it when
    they are below it, else absolute; None: absolute); CliError naming the cause."""
    import os

    from gait_planner.model.urdf_import import UrdfError, draft_scene

    def written(p: str | Path) -> str:  # relative only below the draft's folder
        p = Path(p).resolve()
        relative = None if folder is None else os.path.relpath(p, folder.resolve())
        return str(p) if relative is None or relative.startswith("..") else relative

    path = Path(args.urdf)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise CliError(f"cannot read the URDF {str(path)!r}: {error}") from None
    locked = {}
    for item in filter(None, (s.strip() for s in args.lock.split(","))):
        joint, _, value = item.partition("=")
        try:
            locked[joint.strip()] = float(value)
        except ValueError:
            raise CliError(f"--lock takes JOINT=RADIANS, got {item!r}") from None
    feet = [f.strip() for f in args.feet.split(",")] if args.feet else None
    dirs = list(args.package_dir) + [str(p) for p in path.resolve().parents]
    try:
        return draft_scene(text, feet=feet, locked=locked, name=args.name, package_dirs=dirs,
                           urdf_file=written(path),
                           robot_dirs=[written(d) for d in args.package_dir],
                           mirror_tolerance=args.mirror_tolerance,
                           leg_clearance=args.leg_clearance)
    except UrdfError as error:
        raise CliError(f"{path}: {error}") from None


def write_draft(draft, out: Path) -> Path:
    """Write the draft's YAML to `out` atomically, after loading it as a scene."""
    from gait_planner.atomic import atomic_target
    from gait_planner.model.loader import SceneError, scene_from_text

    try:
        scene_from_text(draft.yaml, out.name, out.parent)
    except SceneError as error:  # the importer's own defect, not the user's
        raise CliError(f"the drafted scene does not load: {error}") from None
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        with atomic_target(out) as tmp:
            tmp.write_text(draft.yaml, encoding="utf-8")
    except OSError as error:
        raise CliError(f"cannot write {str(out)!r}: {error.strerror or error}") from None
    return out


def _from_urdf(args: argparse.Namespace) -> int:
    draft = draft_of(args, None if args.out is None else Path(args.out).parent)
    if args.out is None:
        sys.stdout.write(draft.yaml)
        return 0
    write_draft(draft, Path(args.out))
    print(f"scene: {args.out} ({len(draft.joints)} joints planned, {len(draft.locked)} locked)")
    return 0
