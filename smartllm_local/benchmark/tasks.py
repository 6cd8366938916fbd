"""Benchmark tasks: one JSON object per line, checked against their world's task schema (household's is
``domains/task.schema.json``).

A task file is read whole and checked line by line; every bad line is
reported as ``file:line: what is wrong`` and no line is skipped silently (blank
lines are not tasks). Beyond the schema, floor plans must be iTHOR scenes,
robots must be in the catalogue, goal types must exist in the floor plan, and
ids must be unique.
"""

from __future__ import annotations

import difflib
import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import jsonschema

from ..domain import Domain, load_domain
from ..errors import TaskFileError, UnknownFloorPlanError, UserError
from ..robots import Catalogue
from ..scoring import Goal, parse_goals
from ..worlds import World, world_of

# SMART-LLM's four categories (this project's benchmark has tasks in each), and LaMMA-P's MAT-THOR
# "vague" commands (imported tasks only).
SMARTLLM_CATEGORIES = ("elemental", "simple", "compound", "complex")
CATEGORIES = (*SMARTLLM_CATEGORIES, "vague")


def check_category(category: str | None) -> None:
    """A ``--category`` filter must name a category (or "uncategorized", for imported tasks)."""
    if category is not None and category not in (*CATEGORIES, "uncategorized"):
        raise UserError(f"--category must be one of {', '.join(CATEGORIES)}, not {category!r}")


@dataclass(frozen=True)
class Task:
    id: str
    category: str
    floor_plan: str
    instruction: str
    robots: tuple[int, ...]
    goals: tuple[Goal, ...]
    trans: int | None
    max_trans: int | None
    feasible: bool
    missing_skills: tuple[str, ...] = ()
    notes: str = ""
    source: str = ""  # file:line

    def _floor_plan_field(self) -> int | str:
        """iTHOR floor plans by number, as task files give them; a site domain's site by name."""
        number = self.floor_plan[len("FloorPlan"):]
        return int(number) if self.floor_plan.startswith("FloorPlan") and number.isdigit() else self.floor_plan

    def as_json(self) -> dict[str, Any]:
        data: dict[str, Any] = {
            "id": self.id, "category": self.category, "floor_plan": self._floor_plan_field(),
            "instruction": self.instruction, "robots": list(self.robots),
            "goals": [g.as_dict() for g in self.goals], "trans": self.trans, "max_trans": self.max_trans,
            "feasible": self.feasible,
        }
        if self.missing_skills:
            data["missing_skills"] = list(self.missing_skills)
        if self.notes:
            data["notes"] = self.notes
        return data


def has_words(instruction: str) -> bool:
    """Whether an instruction has a letter or digit: one of only spaces or punctuation says nothing to plan (a
    model given one would invent a task)."""
    return any(ch.isalnum() for ch in instruction)


def check_task(data: Any, catalogue: Catalogue, where: str,
               domain: Domain | None = None) -> tuple[Task | None, list[str]]:
    """Check one decoded line (of ``domain``'s tasks, default household); return the task and the problems found."""
    return _check_line(data, catalogue, where, world_of(domain or load_domain()))


def _check_line(data: Any, catalogue: Catalogue, where: str, world: World) -> tuple[Task | None, list[str]]:
    """:func:`check_task` in ``world`` (which a task file's lines share: making it is most of a line's check)."""
    problems = []
    rules = world.task_rules()
    validator = jsonschema.Draft202012Validator(rules.schema)
    for error in sorted(validator.iter_errors(data), key=lambda e: list(e.absolute_path)):
        field = "/".join(str(p) for p in error.absolute_path) or "(line)"
        problems.append(f"{where}: {field}: {error.message}")
    if problems:
        return None, problems
    if not has_words(data["instruction"]):
        return None, [f"{where}: instruction: {data['instruction']!r} has no words: say what the robots should do"]
    try:
        scene = world.scene_name(data["floor_plan"])
    except UnknownFloorPlanError as exc:
        return None, [f"{where}: floor_plan: {exc}"]
    unknown = [r for r in data["robots"] if r not in catalogue.robots]
    if unknown:
        problems.append(f"{where}: robots: {unknown} are not in the catalogue {catalogue.path}")
    try:
        goals = parse_goals(data["goals"], where="goals", states=rules.goal_states)
    except TaskFileError as exc:
        return None, problems + [f"{where}: {exc}"]
    types = {t.lower() for t in world.scene(scene).types}  # a floor plan's types and their slices; a site's entries
    for goal in goals:
        for name in (goal.name, *goal.contains):
            if name.lower() not in types:
                problems.append(f"{where}: goals: there is no {name!r} in {scene}")
    if data["trans"] is not None and data["max_trans"] is not None and data["trans"] > data["max_trans"]:
        problems.append(f"{where}: trans ({data['trans']}) is larger than max_trans ({data['max_trans']})")
    if problems:
        return None, problems
    task = Task(
        id=data["id"], category=data["category"], floor_plan=scene, instruction=data["instruction"].strip(),
        robots=tuple(data["robots"]), goals=goals, trans=data["trans"], max_trans=data["max_trans"],
        feasible=data["feasible"], missing_skills=tuple(data.get("missing_skills", ())),
        notes=data.get("notes", ""), source=where,
    )
    return task, []


def given_task(instruction: str, floor_plan: str, robots: Sequence[int]) -> Task:
    """A task given on the command line rather than read from a task file: an instruction, a scene and a team,
    with no goal conditions to score it by (what a method plans from, as it plans a benchmark task)."""
    return Task(id="given", category="", floor_plan=floor_plan, instruction=instruction, robots=tuple(robots),
                goals=(), trans=None, max_trans=None, feasible=True, source="the command line")


def load_tasks(paths: Path | str | Sequence[Path | str] | None = None, *,
               catalogue: Catalogue | None = None, domain: Domain | None = None) -> list[Task]:
    """Read task files (default: the domain's benchmark/*.jsonl, household's by default) and check every line.

    Raises:
        TaskFileError: listing every bad line as ``file:line: problem``.
    """
    domain = domain or load_domain()
    if paths is None:
        paths = domain.task_files()
    elif isinstance(paths, (str, Path)):
        paths = [paths]
    catalogue = catalogue or domain.catalogue
    world = world_of(domain)
    tasks: list[Task] = []
    problems: list[str] = []
    seen: dict[str, str] = {}
    for path in map(Path, paths):
        try:
            lines = path.read_text(encoding="utf-8").splitlines()
        except OSError as exc:
            raise TaskFileError(f"cannot read task file {path}: {exc.strerror or exc}") from exc
        except UnicodeDecodeError as exc:
            raise TaskFileError(f"task file {path} is not UTF-8 text ({exc.reason})") from exc
        for number, line in enumerate(lines, start=1):
            if not line.strip():
                continue
            where = f"{path}:{number}"
            try:
                data = json.loads(line)
            except ValueError as exc:
                problems.append(f"{where}: not valid JSON ({exc})")
                continue
            task, found = _check_line(data, catalogue, where, world)
            problems += found
            if task is None:
                continue
            if task.id in seen:
                problems.append(f"{where}: id {task.id!r} is already used at {seen[task.id]}")
                continue
            seen[task.id] = where
            tasks.append(task)
    if problems:
        raise TaskFileError("\n".join(problems))
    return tasks


def find_task(tasks: Iterable[Task], task_id: str) -> Task:
    """The task with this id; an unknown id gets the closest ids as suggestions."""
    tasks = list(tasks)
    for task in tasks:
        if task.id == task_id:
            return task
    close = difflib.get_close_matches(task_id, [t.id for t in tasks], n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    raise UserError(f"no task {task_id!r} in the task file(s){hint}")
