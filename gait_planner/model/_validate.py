"""Checked reading of parsed scene YAML: the error type and the primitive checks.

Every check either returns the value converted to its final type (floats, tuples, read-only
mappings) or raises `SceneError` naming the file, the key path (`bodies[2].mass`) and the
reason. `gait_planner.model.loader` composes these into the scene schema.
"""

from __future__ import annotations

import enum
import math
import re
from types import MappingProxyType
from typing import Any, Iterable, NoReturn, TypeVar

import yaml

from gait_planner.model.scene import Body, Gait, Phase

NAME_PATTERN = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
"""Names of bodies, points, joints, contacts and phases: identifiers (URDF- and ROS-safe)."""

E = TypeVar("E", bound=enum.Enum)


class SceneError(ValueError):
    """A scene file or scene name that cannot be used; the message says where and why.

    Attributes:
        file: the scene file's name (e.g. "walker3d.yaml"), or None.
        key: the key path inside the file (e.g. "bodies[2].mass"), or None.
        reason: the sentence saying what is wrong.
    """

    def __init__(self, reason: str, *, file: str | None = None, key: str | None = None):
        self.file, self.key, self.reason = file, key, reason
        super().__init__(": ".join(p for p in (file, key, reason) if p))


def join(path: str, key: str | int) -> str:
    """The key path of `key` inside `path`: "bodies" + 2 -> "bodies[2]", + "mass" -> ".mass"."""
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else str(key)


def describe(value: Any) -> str:
    """A short description of a parsed YAML value for error messages."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return f"{str(value).lower()} (a boolean)"
    if isinstance(value, (int, float, str)):
        return repr(value)
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    return f"a {type(value).__name__}"


class _DuplicateKeyMapping(dict):
    """A parsed YAML mapping that remembers keys given more than once."""

    duplicates: tuple = ()


class _SceneYamlLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):  # type: ignore[misc]
    """yaml's safe loader (plain data only; the C parser if built) whose mappings record
    duplicate keys instead of silently keeping the last one."""


def _construct_mapping(loader, node: yaml.MappingNode) -> dict:
    loader.flatten_mapping(node)
    result, duplicates = _DuplicateKeyMapping(), []
    for key_node, value_node in node.value:
        key = loader.construct_object(key_node, deep=True)
        if not isinstance(key, (str, int, float, bool)) and key is not None:
            raise yaml.constructor.ConstructorError(
                None, None, "mapping keys must be scalars", key_node.start_mark
            )
        if key in result:
            duplicates.append(key)
        result[key] = loader.construct_object(value_node, deep=True)
    result.duplicates = tuple(duplicates)
    return result


_SceneYamlLoader.add_constructor(
    yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping
)


def parse_yaml(text: str, file: str) -> Any:
    """Parse YAML safely (plain data only); a syntax error becomes a SceneError."""
    try:
        return yaml.load(text, Loader=_SceneYamlLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as error:
        raise SceneError(f"is not valid YAML: {error}", file=file) from None


class Checker:
    """Primitive checks of parsed YAML values; failures name `file` and the key path."""

    def __init__(self, file: str):
        self.file = file
        self.warnings: list[str] = []  # logged by the loader once the whole scene is valid
        self.notes: list[str] = []  # what the file acknowledged (logged at INFO level)

    def fail(self, key: str, reason: str) -> NoReturn:
        raise SceneError(reason, file=self.file, key=key or "(top level)")

    def mapping(
        self, value: Any, key: str, required: Iterable[str] = (), optional: Iterable[str] = ()
    ) -> dict:
        """A mapping with string keys; with `required`/`optional` given, exactly those keys."""
        if not isinstance(value, dict):
            self.fail(key, f"must be a mapping, got {describe(value)}")
        for duplicate in getattr(value, "duplicates", ()):
            self.fail(join(key, str(duplicate)), "is given more than once")
        for k in value:
            if not isinstance(k, str):
                self.fail(join(key, str(k)), f"keys must be strings, got {describe(k)}")
        required, optional = tuple(required), tuple(optional)
        if required or optional:
            allowed = required + optional
            for k in value:
                if k not in allowed:
                    self.fail(join(key, k), f"unknown key (allowed keys: {', '.join(allowed)})")
            for k in required:
                if k not in value:
                    self.fail(join(key, k), "required key is missing")
        return dict(value)

    def sequence(self, value: Any, key: str, length: int | None = None) -> list:
        if not isinstance(value, list):
            self.fail(key, f"must be a list, got {describe(value)}")
        if length is not None and len(value) != length:
            self.fail(key, f"must be a list of {length} numbers, got {len(value)} entries")
        return value

    def number(
        self, value: Any, key: str, *, positive: bool = False, minimum: float | None = None
    ) -> float:
        """A finite float (bool is not a number); optionally > 0 or >= `minimum`."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(key, f"must be a number, got {describe(value)}")
        value = float(value)
        if not math.isfinite(value):
            self.fail(key, f"must be a finite number, got {value}")
        if positive and not value > 0.0:
            self.fail(key, f"must be a positive number, got {value}")
        if minimum is not None and value < minimum:
            self.fail(key, f"must be a number >= {minimum}, got {value}")
        return value

    def integer(self, value: Any, key: str, *, minimum: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(key, f"must be an integer, got {describe(value)}")
        if value < minimum:
            self.fail(key, f"must be an integer >= {minimum}, got {value}")
        return value

    def vector(self, value: Any, key: str, length: int = 3) -> tuple[float, ...]:
        items = self.sequence(value, key, length)
        return tuple(self.number(v, join(key, i)) for i, v in enumerate(items))

    def boolean(self, value: Any, key: str) -> bool:
        if not isinstance(value, bool):
            self.fail(key, f"must be true or false, got {describe(value)}")
        return value

    def string(self, value: Any, key: str) -> str:
        if not isinstance(value, str):
            self.fail(key, f"must be a string, got {describe(value)}")
        return value

    def name(self, value: Any, key: str) -> str:
        """A name: a letter, then letters, digits and underscores."""
        value = self.string(value, key)
        if not NAME_PATTERN.fullmatch(value):
            self.fail(key, f"must be a name (a letter, then letters, digits or '_'), got {value!r}")
        return value

    def choice(self, value: Any, key: str, enum_type: type[E]) -> E:
        options = [member.value for member in enum_type]
        if isinstance(value, str) and value in options:
            return enum_type(value)
        self.fail(key, f"must be one of {', '.join(options)}, got {describe(value)}")

    def known(self, value: str, key: str, known: Iterable[str], what: str) -> str:
        """`value` must be one of `known` (e.g. body names); `what` names them in errors."""
        known = list(known)
        if value not in known:
            listing = ", ".join(known) if known else "none"
            self.fail(key, f"unknown {what} {value!r} (known: {listing})")
        return value

    def point(self, value: Any, key: str, body: Body) -> str:
        """The name of one of `body`'s points."""
        point = self.name(value, key)
        if point not in body.points:
            listing = ", ".join(body.points) or "none"
            self.fail(key, f"body {body.name!r} has no point {point!r} (its points: {listing})")
        return point

    def named_list(self, value: Any, key: str, what: str) -> list:
        """A list of mappings with distinct `name`s (of `what`s), checked up front."""
        items = self.sequence(value, key)
        names = []
        for i, item in enumerate(items):
            entry = self.mapping(item, join(key, i))
            if "name" not in entry:
                self.fail(join(join(key, i), "name"), "required key is missing")
            names.append(self.name(entry["name"], join(join(key, i), "name")))
        self.unique(names, lambda i: join(join(key, i), "name"), what)
        return items

    def unique(self, names: list[str], key_of, what: str) -> None:
        """Refuse a name used twice; `key_of(i)` is the key path of entry i's name."""
        first: dict[str, int] = {}
        for i, name in enumerate(names):
            if name in first:
                self.fail(key_of(i), f"duplicate {what} name {name!r} "
                                     f"(first used at index {first[name]})")
            first[name] = i

    def free_value(self, value: Any, key: str) -> Any:
        """A pass-through option value: finite numbers, strings, bools, lists, mappings.

        Lists become tuples and mappings read-only, so the result is immutable.
        """
        if isinstance(value, (bool, str, int)):
            return value
        if isinstance(value, float):
            return self.number(value, key)
        if isinstance(value, list):
            return tuple(self.free_value(v, join(key, i)) for i, v in enumerate(value))
        if isinstance(value, dict):
            items = self.mapping(value, key)
            return MappingProxyType({k: self.free_value(v, join(key, k)) for k, v in items.items()})
        self.fail(
            key, f"must be a finite number, string, boolean, list or mapping, got {describe(value)}"
        )


# ---------------------------------------------------------------------------- the gait block


def check_gait(c: Checker, value: Any, bodies: tuple[Body, ...], contacts) -> Gait:
    """The `gait` block of a scene, its contacts and mirror pairs checked against the scene."""
    key = "gait"
    g = c.mapping(
        value,
        key,
        required=("step_length", "base_time_step", "scaling_bounds", "friction_coefficient",
                  "phases"),
        optional=("cost", "mirror", "options", "start", "stop"),
    )
    bkey = join(key, "scaling_bounds")
    lower, upper = c.vector(g["scaling_bounds"], bkey, 2)
    if not lower > 0.0:
        c.fail(join(bkey, 0), f"the lower scaling bound must be positive, got {lower}")
    if upper < lower:
        c.fail(join(bkey, 1), f"the upper scaling bound must be >= the lower one {lower}, "
                              f"got {upper}")
    cost = c.name(g.get("cost", "kinetic_energy"), join(key, "cost"))
    options = c.free_value(c.mapping(g.get("options", {}), join(key, "options")),
                           join(key, "options"))
    phases, mirror = _phases(c, g["phases"], contacts), _mirror(c, g.get("mirror", {}), bodies)
    _check_periodic_phases(c, phases, mirror, contacts)
    start = _end_phases(c, g.get("start", []), "start", contacts, 0)
    stop = _end_phases(c, g.get("stop", []), "stop", contacts, len(start))
    c.unique([p.name for p in phases + start + stop], lambda n: join(key, "start/stop"),
             "phase")
    return Gait(
        phases=phases,
        step_length=c.number(g["step_length"], join(key, "step_length"), positive=True),
        mirror=mirror,
        base_time_step=c.number(g["base_time_step"], join(key, "base_time_step"), positive=True),
        scaling_bounds=(lower, upper),
        friction_coefficient=c.number(
            g["friction_coefficient"], join(key, "friction_coefficient"), positive=True
        ),
        cost=cost,
        options=options,
        start=start,
        stop=stop,
    )


def _end_phases(c: Checker, value: Any, key: str, contacts, first: int) -> tuple[Phase, ...]:
    """The `gait.start` or `gait.stop` phases ({name, contacts, intervals} each; a scaling
    of its own, numbered from `first`): contacts known, the start's first phase and the
    stop's last holding at least one contact (they stand)."""
    key = join("gait", key)
    known = [contact.name for contact in contacts]
    phases = []
    for i, item in enumerate(c.named_list(value, key, "phase")):
        pkey = join(key, i)
        p = c.mapping(item, pkey, required=("name", "contacts", "intervals"))
        ckey = join(pkey, "contacts")
        held = [c.known(c.name(v, join(ckey, n)), join(ckey, n), known, "contact")
                for n, v in enumerate(c.sequence(p["contacts"], ckey))]
        c.unique(held, lambda n: join(ckey, n), "contact")
        phases.append(Phase(name=p["name"], contacts=tuple(held), scaling=first + i,
                            intervals=c.integer(p["intervals"], join(pkey, "intervals"),
                                                minimum=1)))
    standing = (phases[0] if key.endswith("start") else phases[-1]) if phases else None
    if standing is not None and not standing.contacts:
        c.fail(key, f"phase {standing.name!r} stands: it must hold contacts")
    return tuple(phases)


def _phases(c: Checker, value: Any, contacts) -> tuple[Phase, ...]:
    key = join("gait", "phases")
    items = c.named_list(value, key, "phase")
    if not items:
        c.fail(key, "must list at least one phase")
    known = [contact.name for contact in contacts]
    phases = []
    for i, item in enumerate(items):
        pkey = join(key, i)
        p = c.mapping(item, pkey, required=("name", "contacts", "scaling", "intervals"))
        ckey = join(pkey, "contacts")
        held = [
            c.known(c.name(v, join(ckey, n)), join(ckey, n), known, "contact")
            for n, v in enumerate(c.sequence(p["contacts"], ckey))
        ]
        c.unique(held, lambda n: join(ckey, n), "contact")
        phases.append(Phase(
            name=p["name"],
            contacts=tuple(held),
            scaling=c.integer(p["scaling"], join(pkey, "scaling"), minimum=0),
            intervals=c.integer(p["intervals"], join(pkey, "intervals"), minimum=1),
        ))
    used = {p.scaling for p in phases}
    for index in range(max(used) + 1):
        if index not in used:
            c.fail(key, f"the phase scaling indices must use every index from 0 to {max(used)}; "
                        f"index {index} is unused")
    return tuple(phases)


def _check_periodic_phases(c: Checker, phases: tuple[Phase, ...], mirror, contacts) -> None:
    """The half cycle's last interval is the mirror image of its first (docs/design.md
    section 5): the last phase must hold the mirror images of the first phase's contacts
    and share its scaling (a walk's left_full after right_full; a run's left stance after
    right stance and flight)."""
    where = {(x.body, x.point): x.name for x in contacts}
    by_name = {x.name: x for x in contacts}
    first, last = phases[0], phases[-1]
    images = sorted(where.get((mirror.get(by_name[n].body, by_name[n].body), by_name[n].point),
                              f"(no mirror image of {n})") for n in first.contacts)
    key = join("gait", "phases")
    if sorted(last.contacts) != images:
        c.fail(key, f"the last phase {last.name!r} must hold the mirror images of the first "
                    f"phase's contacts, {images} (its last interval is the mirror image of "
                    f"the first), got {sorted(last.contacts)}")
    if last.scaling != first.scaling:
        c.fail(key, f"the last phase {last.name!r} must share the first phase's scaling "
                    f"{first.scaling} (one phase across the half cycle's end), got {last.scaling}")


def _mirror(c: Checker, value: Any, bodies: tuple[Body, ...]) -> MappingProxyType:
    """The symmetric mirror map over all bodies (unnamed bodies mirror onto themselves)."""
    key = join("gait", "mirror")
    by_name = {b.name: b for b in bodies}
    pairs: dict[str, str] = {}
    for name, other in c.mapping(value, key).items():
        mkey = join(key, name)
        c.known(name, mkey, by_name, "body")
        c.known(c.name(other, mkey), mkey, by_name, "body")
        for a, b in ((name, other), (other, name)):
            if pairs.get(a, b) != b:
                c.fail(mkey, f"body {a!r} cannot mirror onto both {pairs[a]!r} and {b!r}")
            pairs[a] = b
        first, second = by_name[name], by_name[other]
        if not (_close(first.mass, second.mass) and all(
            _close(x, y) for x, y in zip(first.inertia, second.inertia)
        )):
            c.fail(mkey, f"mirror images need equal mass and inertia: {name!r} has mass "
                         f"{first.mass} and inertia {first.inertia}, {other!r} has mass "
                         f"{second.mass} and inertia {second.inertia}")
    return MappingProxyType({b.name: pairs.get(b.name, b.name) for b in bodies})


def _close(a: float, b: float) -> bool:
    return math.isclose(a, b, rel_tol=1e-12, abs_tol=0.0)
