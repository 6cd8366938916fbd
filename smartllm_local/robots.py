"""The robot catalogue: which robots exist, what each can do and how much it can lift.

A domain's robots are its catalogue (see :mod:`.domain`). ``--catalogue`` gives an AI2-THOR domain
other robots as a JSON file: robots, each with an ``id``, a ``name``, its ``skills`` and its
``mass_capacity`` in kg, and optionally extra ``skills`` mapped onto AI2-THOR actions. A team is an
ordered list of catalogue robots; inside a plan, ``robots[i]`` is the i-th.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import CatalogueError
from .skills import DEFAULT_SKILLS, Skill, SkillSet, thor_skill


@dataclass(frozen=True)
class Robot:
    id: int
    name: str
    skills: frozenset[str]
    mass_capacity: float
    kind: str = ""  # a site domain's robot kind ("aerial", "ground"): which places it can reach
    capacities: tuple[tuple[str, float], ...] = ()  # a site domain's capacities, by name

    def capacity(self, name: str) -> float:
        """A site domain's capacity (0 when the robot has none)."""
        return dict(self.capacities).get(name, 0.0)

    def describe(self) -> str:
        if self.capacities:
            held = "; ".join(f"{name} {value:g}" for name, value in self.capacities)
            return f"{self.name} ({self.kind or 'robot'}; skills: {', '.join(sorted(self.skills))}; {held})"
        return f"{self.name} (skills: {', '.join(sorted(self.skills))}; carries up to {self.mass_capacity:g} kg)"


@dataclass(frozen=True)
class Catalogue:
    robots: dict[int, Robot]
    skills: SkillSet
    path: str

    def team(self, ids: Iterable[int]) -> list[Robot]:
        """The robots with these ids, in order; unknown ids are an error naming the known ones."""
        ids = list(ids)
        if not ids:
            raise CatalogueError("a team needs at least one robot id")
        unknown = [i for i in ids if i not in self.robots]
        if unknown:
            known = f"{min(self.robots)}-{max(self.robots)}" if self.robots else "none"
            raise CatalogueError(f"unknown robot id(s) {unknown} in {self.path}: known ids are {known}")
        if len(set(ids)) != len(ids):
            raise CatalogueError(f"robot ids repeat in {ids}: a robot can join a team once")
        return [self.robots[i] for i in ids]


def parse_robot_ids(text: str) -> list[int]:
    """Parse ``"1,2,3"`` (or ``"1 2 3"``) into robot ids."""
    parts = [p for p in text.replace(",", " ").split() if p]
    try:
        ids = [int(p) for p in parts]
    except ValueError:
        raise CatalogueError(f"--robots takes catalogue ids such as 1,2,3; got {text!r}") from None
    if not ids:
        raise CatalogueError("--robots needs at least one catalogue id, such as 1,2,3")
    return ids


def load_catalogue(path: str | Path) -> Catalogue:
    """Read and check a JSON catalogue file; every problem is reported with its place in the file."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise CatalogueError(f"cannot read robot catalogue {path}: {exc.strerror or exc}") from exc
    except ValueError as exc:
        raise CatalogueError(f"{path}: not valid JSON ({exc})") from exc
    if not isinstance(data, dict) or not isinstance(data.get("robots"), list):
        raise CatalogueError(f'{path}: expected an object with a "robots" list')
    skills = _extra_skills(path, data.get("skills", []))
    robots: dict[int, Robot] = {}
    for k, entry in enumerate(data["robots"]):
        where = f"{path}: robots[{k}]"
        robot = _robot(where, entry, skills)
        if robot.id in robots:
            raise CatalogueError(f"{where}: id {robot.id} is used twice")
        robots[robot.id] = robot
    return Catalogue(robots=robots, skills=skills, path=str(path))


def _extra_skills(path: Path, entries: Any) -> SkillSet:
    """SMART-LLM's skills and the catalogue's own, each read as a domain file reads its ``[skills.NAME]``."""
    if not isinstance(entries, list):
        raise CatalogueError(f'{path}: "skills" must be a list of {{"name", "action", "arguments"}}')
    skills: list[Skill] = list(DEFAULT_SKILLS)
    names = {s.name for s in skills}
    for k, entry in enumerate(entries):
        where = f"{path}: skills[{k}]"
        if not isinstance(entry, dict) or not isinstance(entry.get("name"), str) or not entry["name"].isidentifier():
            raise CatalogueError(f'{where}: needs a "name" that is a Python identifier')
        if entry["name"] in names:
            raise CatalogueError(f"{where}: skill {entry['name']} is already defined")
        skill = thor_skill(entry["name"], {key: value for key, value in entry.items() if key != "name"})
        if isinstance(skill, list):
            raise CatalogueError(f"{where}: {'; '.join(skill)}")
        skills.append(skill)
        names.add(skill.name)
    return SkillSet(skills)


def _robot(where: str, entry: Any, skills: SkillSet) -> Robot:
    if not isinstance(entry, dict):
        raise CatalogueError(f"{where}: expected an object")
    rid = entry.get("id")
    if not isinstance(rid, int) or isinstance(rid, bool) or rid < 0:
        raise CatalogueError(f'{where}: "id" must be a non-negative integer')
    robot_skills = entry.get("skills")
    if not isinstance(robot_skills, list) or not all(isinstance(s, str) for s in robot_skills):
        raise CatalogueError(f'{where}: "skills" must be a list of skill names')
    unknown = sorted(set(robot_skills) - set(skills))
    if unknown:
        raise CatalogueError(f"{where}: unknown skill(s) {unknown}; known: {', '.join(skills)}")
    capacity = entry.get("mass_capacity", entry.get("mass"))
    if not isinstance(capacity, (int, float)) or isinstance(capacity, bool) or capacity < 0:
        raise CatalogueError(f'{where}: "mass_capacity" must be a non-negative number (kg)')
    return Robot(id=rid, name=str(entry.get("name") or f"robot{rid}"), skills=frozenset(robot_skills),
                 mass_capacity=float(capacity))


def team_skills(team: Sequence[Robot]) -> frozenset[str]:
    """What a team can do together: the union of its members' skills."""
    return frozenset().union(*(r.skills for r in team)) if team else frozenset()


def team_lift(team: Sequence[Robot]) -> float:
    """What a team lifts together: every member's mass capacity, as the world pools it (a teammate with a free
    hand within reach helps lift, whatever its skills)."""
    return sum(r.mass_capacity for r in team)
