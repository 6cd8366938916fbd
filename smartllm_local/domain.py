"""Domains: which robots exist, what they can do, the world they work in and how goals are judged.

A domain is a folder::

    DIR/domain.toml                    the skills, robots and world (schema-checked)
    DIR/prompts/                       the prompts' worked examples (laid out as household's)
    DIR/benchmark/tasks.jsonl          its benchmark tasks, then any other *.jsonl (optional)
    DIR/benchmark/reference_plans/     a plan per feasible task that scores SR = 1 (optional)
    DIR/benchmark/split.toml           its development/test split (optional)

Its world is AI2-THOR (``world = "ai2thor"``: tasks name iTHOR floor plans, each skill performs an
AI2-THOR action on objects with the affordances its arguments name, a team pools mass to lift) or a
2-D site (``[world.locations|regions|objects.NAME]`` tables): there a skill names the *effect* it has
in the site simulator (``move``, ``photograph``, ``patrol``), so a lab may call it what its robots call
it; robots carry the numeric capacities the domain declares, and a skill that ``pools`` a capacity is
done by a team whose members' capacities add up. ``household`` (SMART-LLM's) and ``patrol`` (its
real-robot experiment) ship in ``domains/``. Every problem in a file is reported as
``file:line: what is wrong; what to do``.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from .errors import UserError
from .resources import data_dir
from .robots import Catalogue, Robot
from .skills import Skill, SkillSet, thor_skill

HOUSEHOLD = "household"
DOMAIN_FILE = "domain.toml"
PROMPTS = "prompts"  # the prompts' worked examples
BENCHMARK = "benchmark"  # the task files and the reference plans
TASKS_FILE = "tasks.jsonl"
SPLIT_FILE = "split.toml"  # the benchmark's development/test split (optional)
PLANS = "reference_plans"
AI2THOR = "ai2thor"

#: What a skill does in the site simulator, and the argument type it takes.
EFFECTS = {"move": "place", "photograph": "object", "patrol": "region"}
#: The kinds of entries a site holds; ``place`` is any of them.
ENTRY_KINDS = ("location", "region", "object")
ARGUMENT_TYPES = (*ENTRY_KINDS, "place")
#: The kind of the planner's notional robots, which reach every place (no robot may declare it).
ANY_KIND = "*"


class DomainError(UserError):
    """A domain file or folder that cannot be used as it is."""


@dataclass(frozen=True)
class Place:
    """A site entry: a location, a region (with an area) or an object, at a point of the 2-D site."""

    name: str
    kind: str
    at: tuple[float, float]
    area: float = 0.0
    reach: frozenset[str] | None = None  # the robot kinds that can get there; None: every kind

    def reachable_by(self, robot: Robot) -> bool:
        return self.reach is None or robot.kind in self.reach or robot.kind == ANY_KIND


@dataclass(frozen=True)
class Domain:
    """A domain: its catalogue (robots and skills), and for a site domain, the site and the skills' effects."""

    name: str
    description: str
    catalogue: Catalogue
    folder: Path
    world: str = "site"  # or AI2THOR
    site: str = ""
    start: str = ""
    places: Mapping[str, Place] = field(default_factory=dict)
    effects: Mapping[str, str] = field(default_factory=dict)  # skill -> move | photograph | patrol
    pools: Mapping[str, str] = field(default_factory=dict)  # skill -> the capacity a team pools for it
    capacities: Mapping[str, str] = field(default_factory=dict)  # capacity -> what it measures

    def benchmark_dir(self) -> Path:
        """Its benchmark: the task files and the reference plans."""
        return self.folder / BENCHMARK

    def task_files(self) -> list[Path]:
        """Its benchmark's task files: benchmark/tasks.jsonl, then any other ``benchmark/*.jsonl`` (household:
        its infeasible tasks)."""
        folder = self.benchmark_dir()
        others = sorted(p for p in folder.glob("*.jsonl") if p.name != TASKS_FILE)
        return [folder / TASKS_FILE, *others]

    def split_file(self) -> Path:
        """Where its benchmark's development/test split is (a domain may have none)."""
        return self.benchmark_dir() / SPLIT_FILE

    def plans_dir(self) -> Path:
        return self.benchmark_dir() / PLANS

    def prompts_dir(self) -> Path:
        """The prompts' worked examples (``examples.json`` and a folder per stage)."""
        return self.folder / PROMPTS

    def place(self, name: str) -> Place | None:
        """The site entry a plan names (case-insensitively), or None."""
        return self.places.get(name) or next((p for p in self.places.values() if p.name.lower() == name.lower()), None)


def pooled(robots: Iterable[Robot], skill: str, capacity: str, place: Place | None = None) -> float:
    """What the robots that have ``skill`` (and, given a place, get there) add up of ``capacity``: a team
    acts with its members' skills, so only they count toward what a call pools (a patrol's area, a camera).
    The executor's site, its infeasibility proof and the planner's team rules all ask this."""
    return sum(r.capacity(capacity) for r in robots if skill in r.skills and (place is None or place.reachable_by(r)))


def builtin_domains() -> list[str]:
    """The domains that ship with the project, household first."""
    names = [p.name for p in data_dir("domains").iterdir()
             if (p / DOMAIN_FILE).is_file() and not p.name.startswith("_")]
    return sorted(names, key=lambda n: (n != HOUSEHOLD, n))


def starter_domain() -> Path:
    """The commented starting domain that ``domain new`` copies."""
    return data_dir("domains") / "_starter"


def load_domain(name_or_dir: str | Path | None = None) -> Domain:
    """A built-in domain by name (default household) or a domain folder (``--catalogue``'s robots in its
    place: :func:`.worlds.with_catalogue`, which asks the domain's world whether it takes them)."""
    name = str(name_or_dir) if name_or_dir is not None else HOUSEHOLD
    folder = Path(name)
    if (folder / DOMAIN_FILE).is_file():
        check_layout(folder)
        domain = read_domain_file(folder / DOMAIN_FILE)
    elif name in builtin_domains():
        domain = _builtin(name)
    else:
        known = builtin_domains()
        close = difflib.get_close_matches(name, known, n=1)
        hint = f"; did you mean {close[0]}?" if close else ""
        raise DomainError(f"no domain {name!r}: give a built-in domain ({', '.join(known)}) or a folder holding "
                          f"{DOMAIN_FILE}{hint}")
    return domain


def check_layout(folder: Path) -> None:
    """Refuse a domain folder in the layout before prompts/ and benchmark/ (examples/, tasks.jsonl and
    reference_plans/ beside domain.toml): read as it is, it would silently have no prompts and no tasks."""
    moves = [(folder / "examples", folder / PROMPTS)] if (folder / "examples").is_dir() else []
    moves += [(path, folder / BENCHMARK / path.name) for path in sorted(folder.glob("*.jsonl")) if path.is_file()]
    if (folder / PLANS).is_dir():
        moves.append((folder / PLANS, folder / BENCHMARK / PLANS))
    if moves:
        what = ", ".join(f"{old}{'/' if old.is_dir() else ''} to {new}{'/' if old.is_dir() else ''}"
                         for old, new in moves)
        raise DomainError(f"{folder} has the old domain layout: move {what} (a domain keeps its prompts' worked "
                          f"examples in {PROMPTS}/, its task files and reference plans in {BENCHMARK}/)")


@cache
def _builtin(name: str) -> Domain:
    return read_domain_file(data_dir("domains") / name / DOMAIN_FILE)


class _Checker:
    """Reads a domain file, collecting problems with their line numbers."""

    def __init__(self, path: Path, text: str):
        self.path, self.lines = path, text.splitlines()
        self.problems: list[str] = []

    def line_of(self, *keys: str) -> int:
        """The line defining ``keys`` (a path such as ("skills", "Patrol", "pools")): the header of the
        longest table it names, then each further ``key =`` line after it; 1 when none is found."""
        def first(pattern: str, start: int) -> int | None:
            compiled = re.compile(pattern)
            return next((k for k in range(start, len(self.lines)) if compiled.match(self.lines[k])), None)

        line, rest = 0, keys
        for depth in range(len(keys), 0, -1):
            dotted = r"\s*\.\s*".join(f'"?{re.escape(k)}"?' for k in keys[:depth])
            found = first(rf"^\s*\[+\s*{dotted}\s*\]+", 0)
            if found is not None:
                line, rest = found, keys[depth:]
                break
        for key in rest:
            found = first(rf'^\s*"?{re.escape(key)}"?\s*=', line)
            if found is not None:
                line = found
        return line + 1

    def fail(self, keys: Iterable[str], message: str) -> None:
        self.problems.append(f"{self.path}:{self.line_of(*keys)}: {message}")

    def fail_robot(self, label: str, message: str) -> None:
        """A problem of one ``[[robots]]`` entry, reported at its ``name =`` line."""
        line = next((k + 1 for k, text in enumerate(self.lines)
                     if re.match(rf'^\s*name\s*=\s*"{re.escape(str(label))}"', text)), self.line_of("robots"))
        self.problems.append(f"{self.path}:{line}: {message}")


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and value == value


def read_domain_file(path: Path) -> Domain:
    """Read and check a domain file; every problem is reported at once, each with its line."""
    try:
        text = path.read_text(encoding="utf-8")
        data = tomllib.loads(text)
    except OSError as exc:
        raise DomainError(f"cannot read domain file {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise DomainError(f"domain file {path} is not UTF-8 text ({exc.reason})") from None
    except tomllib.TOMLDecodeError as exc:
        raise DomainError(f"{path}: not valid TOML: {exc}") from None
    check = _Checker(path, text)
    name = data.get("name")
    if not isinstance(name, str) or not name.isidentifier():
        check.fail(["name"], 'needs name = "..." (letters, digits and underscores)')
        name = path.parent.name
    if data.get("world") == AI2THOR:
        return _read_ai2thor(check, data, name)
    known = {"name", "description", "start", "site", "capacities", "skills", "robots", "world"}
    for key in sorted(set(data) - known):
        check.fail([key], f"unknown key {key!r}; a domain file has {', '.join(sorted(known))}")
    site = data.get("site", "site")
    if not isinstance(site, str) or not site.strip():
        check.fail(["site"], 'site must name the site, e.g. site = "campus"')
    capacities = _capacities(check, data.get("capacities", {}))
    places = _places(check, data.get("world"))
    effects, pools, skills = _skills(check, data.get("skills"), capacities, places)
    if "photograph" in effects.values() and "camera_range" not in capacities:
        check.fail(["capacities"], 'a skill photographs, so [capacities] needs camera_range = "metres from '
                                   'which a robot can take a picture"')
    named = set(data["skills"]) if isinstance(data.get("skills"), dict) else set()  # a bad skill is reported once
    robots = _robots(check, data.get("robots"), named, capacities)
    start = data.get("start")
    if not isinstance(start, str) or start not in places:
        check.fail(["start"], f'start must name the site entry every robot starts at, e.g. start = "Base"; '
                              f"got {start!r}")
    if check.problems:
        raise DomainError("\n".join(check.problems))
    catalogue = Catalogue(robots={r.id: r for r in robots}, skills=SkillSet(skills), path=str(check.path))
    return Domain(name=name, description=str(data.get("description", "")), catalogue=catalogue,
                  folder=check.path.parent, site=str(site), start=str(start), places=places, effects=effects,
                  pools=pools, capacities=capacities)


def _read_ai2thor(check: _Checker, data: dict[str, Any], name: str) -> Domain:
    """An AI2-THOR domain: skills that perform AI2-THOR actions, robots that lift up to a mass; its world
    is the iTHOR floor plans its tasks name."""
    known = {"name", "description", "world", "skills", "robots"}
    for key in sorted(set(data) - known):
        check.fail([key], f"unknown key {key!r}; an AI2-THOR domain file has {', '.join(sorted(known))}")
    table = data.get("skills")
    skills: list[Skill] = []
    if not isinstance(table, dict) or not table:
        check.fail(["skills"], 'needs skills: [skills.NAME] tables with action = "<AI2-THOR action>" (or '
                               'effect = "move") and arguments = [affordances]')
        table = {}
    for skill_name, entry in table.items():
        skill = thor_skill(skill_name, entry) if isinstance(entry, dict) else [f"skills.{skill_name} must be a table"]
        if isinstance(skill, list):
            for problem in skill:
                check.fail(["skills", skill_name], problem)
        else:
            skills.append(skill)
    capacities = {"mass_capacity": "kilograms it lifts (robots lifting together add theirs)"}
    robots = _robots(check, data.get("robots"), set(table), capacities, kinds=False)
    if check.problems:
        raise DomainError("\n".join(check.problems))
    catalogue = Catalogue(robots={r.id: r for r in robots}, skills=SkillSet(skills), path=str(check.path))
    return Domain(name=name, description=str(data.get("description", "")), catalogue=catalogue,
                  folder=check.path.parent, world=AI2THOR)


def _capacities(check: _Checker, table: Any) -> dict[str, str]:
    if not isinstance(table, dict):
        check.fail(["capacities"], "[capacities] maps each capacity to what it measures, "
                                   'e.g. visibility_area = "square metres a robot sees at once"')
        return {}
    out = {}
    for key, meaning in table.items():
        if not key.isidentifier() or not isinstance(meaning, str):
            check.fail(["capacities", key], f"capacity {key!r}: give what it measures as text")
            continue
        out[key] = meaning
    return out


def _places(check: _Checker, world: Any) -> dict[str, Place]:
    if not isinstance(world, dict):
        check.fail(["world"], 'needs world = "ai2thor" (AI2-THOR\'s floor plans) or a site: [world.locations.NAME], '
                              "[world.regions.NAME], [world.objects.NAME] tables, each with at = [x, y]")
        return {}
    places: dict[str, Place] = {}
    for plural in sorted(set(world) - {f"{k}s" for k in ENTRY_KINDS}):
        check.fail(["world", plural], f"unknown world table {plural!r}; the site has locations, regions and objects")
    for kind in ENTRY_KINDS:
        table = world.get(f"{kind}s", {})
        if not isinstance(table, dict):
            check.fail(["world", f"{kind}s"], f"world.{kind}s must be tables such as [world.{kind}s.NAME]")
            continue
        for name, entry in table.items():
            where = ["world", f"{kind}s", name]
            if not name.isidentifier() or len(name) > 60:
                check.fail(where, f"{name!r} must be a name of letters, digits and underscores (plans quote it)")
                continue
            if name.lower() in {p.lower() for p in places}:
                check.fail(where, f"{name} is defined twice; each site entry needs a name of its own")
                continue
            if not isinstance(entry, dict):
                check.fail(where, f"world.{kind}s.{name} must be a table with at = [x, y]")
                continue
            allowed = {"at", "reach", "description"} | ({"area"} if kind == "region" else set())
            for key in sorted(set(entry) - allowed):
                check.fail([*where, key], f"{name}: unknown key {key!r}; a {kind} has {', '.join(sorted(allowed))}")
            at = entry.get("at")
            if not (isinstance(at, list) and len(at) == 2 and all(_number(v) for v in at)):
                check.fail(where, f"{name}: at must be [x, y] in metres")
                continue
            area = entry.get("area", 0.0)
            if kind == "region" and (not _number(area) or area <= 0):
                check.fail(where, f"{name}: a region needs area = square metres, above 0")
                area = 0.0
            reach = entry.get("reach")
            if reach is not None and not (isinstance(reach, list) and reach and all(isinstance(k, str) for k in reach)):
                check.fail([*where, "reach"], f"{name}: reach lists the robot kinds that can get there, "
                                              'e.g. reach = ["aerial"]')
                continue
            places[name] = Place(name, kind, (float(at[0]), float(at[1])), float(area),
                                 frozenset(reach) if reach is not None else None)
    return places


def _skills(check: _Checker, table: Any, capacities: Mapping[str, str],
            places: Mapping[str, Place]) -> tuple[dict[str, str], dict[str, str], list[Skill]]:
    effects: dict[str, str] = {}
    pools: dict[str, str] = {}
    skills: list[Skill] = []
    if not isinstance(table, dict) or not table:
        check.fail(["skills"], 'needs skills: [skills.NAME] tables with effect = "move", "photograph" or "patrol"')
        return effects, pools, skills
    for name, entry in table.items():
        where = ["skills", name]
        if not name.isidentifier():
            check.fail(where, f"skill {name!r} must be a Python identifier (plans call it)")
            continue
        if not isinstance(entry, dict):
            check.fail(where, f"skills.{name} must be a table with effect = ...")
            continue
        for key in sorted(set(entry) - {"effect", "pools", "description"}):
            check.fail([*where, key], f"skill {name}: unknown key {key!r}; a skill has effect, pools and description")
        effect = entry.get("effect")
        if not isinstance(effect, str) or effect not in EFFECTS:
            check.fail(where, f"skill {name}: effect must be one of {', '.join(EFFECTS)}, got {effect!r}")
            continue
        argument = EFFECTS[effect]
        if argument != "place" and not any(p.kind == argument for p in places.values()):
            check.fail(where, f"skill {name} takes a {argument}, and the site has none: add a "
                              f"[world.{argument}s.NAME] table")
        pool = entry.get("pools")
        if pool is not None:
            if not isinstance(pool, str) or pool not in capacities:
                check.fail([*where, "pools"], f"skill {name} pools {pool!r}, which is not under [capacities]")
            else:
                pools[name] = pool
        if effect == "patrol" and name not in pools and pool is None:
            check.fail(where, f"skill {name} patrols, so it needs pools = the capacity a team adds up to cover a "
                              'region\'s area, e.g. pools = "visibility_area"')
        effects[name] = effect
        # A move is the planner's go-to (the action "" that AI2-THOR's GoToObject has): other calls act
        # where it went.
        skills.append(Skill(name, "" if effect == "move" else effect, (argument,), 1))
    return effects, pools, skills


def _robots(check: _Checker, entries: Any, names: set[str], capacities: Mapping[str, str], *,
            kinds: bool = True) -> list[Robot]:
    """The ``[[robots]]`` entries; a site's robots have a kind, and AI2-THOR's a mass_capacity alone."""
    fields = "id, name, kind, skills" if kinds else "id, name, skills"
    if not isinstance(entries, list) or not entries:
        check.fail(["robots"], f"needs robots: [[robots]] tables with {fields} and each capacity")
        return []
    robots: list[Robot] = []
    for k, entry in enumerate(entries):
        label = entry.get("name", f"robots[{k}]") if isinstance(entry, dict) else f"robots[{k}]"
        if not isinstance(entry, dict):
            check.fail(["robots"], f"robots[{k}] must be a [[robots]] table")
            continue
        allowed = {"id", "name", *(["kind"] if kinds else []), "skills", *capacities}
        for key in sorted(set(entry) - allowed):
            check.fail_robot(label, f"robot {label}: unknown key {key!r}; a robot has {fields}"
                             + (f" and the capacities {', '.join(capacities)}" if capacities else ""))
        rid = entry.get("id")
        if not isinstance(rid, int) or isinstance(rid, bool) or rid < 0:
            check.fail_robot(label, f"robot {label}: id must be a non-negative integer (teams are given as ids, "
                                    "e.g. --robots 1,2)")
            continue
        if rid in {r.id for r in robots}:
            check.fail_robot(label, f"robot {label}: id {rid} is used twice")
            continue
        kind = entry.get("kind", "")
        if kinds and (not isinstance(kind, str) or not kind.isidentifier()):
            check.fail_robot(label, f'robot {label}: kind must be a word such as "aerial" or "ground" '
                                    "(place reach lists kinds)")
        robot_skills = entry.get("skills")
        if not isinstance(robot_skills, list) or not all(isinstance(s, str) for s in robot_skills):
            check.fail_robot(label, f"robot {label}: skills must list skill names")
            continue
        for unknown in [s for s in robot_skills if s not in names]:
            close = difflib.get_close_matches(unknown, names, n=1)
            check.fail_robot(label, f"robot {label} has skill {unknown!r}, which the domain does not define"
                             + (f"; did you mean {close[0]}?" if close else f"; define it as [skills.{unknown}]"))
        values = {}
        for capacity in capacities:
            value = entry.get(capacity)
            if not _number(value) or value < 0:
                check.fail_robot(label, f"robot {label}: needs {capacity} = a number of 0 or more "
                                        f"({capacities[capacity]})")
                continue
            values[capacity] = float(value)
        name = str(entry.get("name") or f"robot{rid}")
        if kinds:
            robots.append(Robot(id=rid, name=name, skills=frozenset(robot_skills), mass_capacity=0.0, kind=str(kind),
                                capacities=tuple(sorted(values.items()))))
        else:
            robots.append(Robot(id=rid, name=name, skills=frozenset(robot_skills),
                                mass_capacity=values.get("mass_capacity", 0.0)))
    return robots
