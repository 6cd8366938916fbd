"""Where a method fails: each feasible task a run did not succeed on, in one of seven kinds of failure.

The kinds are tried in the order a task goes through a method, and the first that applies is the task's,
so they are exclusive; the last two cover every plan that ran, so they are exhaustive (docs/metrics.md
defines each). A task's stated goals are its goal stage's ``goals.txt`` (where the method ran the stage), with
the holders the goal-planner read from the model's steps in their place (its allocation record's ``placements``:
the goal it planned for), and its end state is what its plan left, replayed from ``allocated.py`` on the
executor the run used (the scene as it began where no plan ran), so a run folder is all it needs, and it reads
that folder only.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..domain import Domain, load_domain
from ..errors import PlanError, SmartLLMError, UserError
from ..goal_language import condition_line, parse_goal_statement
from ..plan_language import read_plan
from ..planner.readings import merge
from ..scoring import Condition, condition_holds, containment
from ..worlds import with_catalogue, world_of
from .goal_accuracy import unmatched
from .results import Line, read_results
from .run_store import RESULTS, RUN_FILE
from .tasks import Task, load_tasks

REFUSED, WRONG_GOAL, NO_PLAN, EXECUTION, GOAL_NOT_INSTRUCTION, SHORT, EXTRA_WORK = (
    "refused", "wrong goal", "no plan found", "failed in execution", "goals met, instruction not",
    "plan short of the goal", "extra work only")
#: The kinds of failure, in the order they are tried.
KINDS = (GOAL_NOT_INSTRUCTION, WRONG_GOAL, REFUSED, NO_PLAN, EXECUTION, SHORT, EXTRA_WORK)
#: The order a report shows them in: the task's way through a method.
SHOWN = (REFUSED, WRONG_GOAL, NO_PLAN, EXECUTION, GOAL_NOT_INSTRUCTION, SHORT, EXTRA_WORK)
_EXECUTION_ERROR = "execution:"  # how the benchmark's results line starts an error its plan's run raised
_REACH_CHECKS = ("planner", "goal check")  # who refuses a stated goal as out of the team's reach
_TIME_LIMIT = "the planner's time limit ran out"  # the goal-planner's error when its search ran out of time


@dataclass(frozen=True)
class Evidence:
    """What one task's run left: its results line, the goals stated (None: none were), the benchmark's
    conditions, and whether a condition holds at the end (asked only where the kind depends on it)."""

    line: Line
    ran: bool  # its plan was executed and scored (neither refused nor ended by an error)
    stated: Sequence[Condition] | None
    truth: Sequence[Condition]
    holds_at_end: Callable[[Condition], bool]


@dataclass(frozen=True)
class Failure:
    id: str
    category: str
    kind: str
    detail: str

    @property
    def counted(self) -> str:
        """Its kind as a report counts it: a refusal by who refused (``refused by model``)."""
        return f"{REFUSED} {self.detail}" if self.kind == REFUSED else self.kind


def classify(ev: Evidence) -> tuple[str, str] | None:
    """The kind of failure of a feasible task and a line saying what went wrong; None where the task
    succeeded, or ran with no ground truth to judge it on (SR None)."""
    line = ev.line
    error = str(line.get("error") or "")
    if line.get("SR") == 1.0 or (ev.ran and line.get("SR") is None):
        return None
    if ev.stated:
        extra, missing = unmatched(ev.stated, ev.truth)
        if ev.ran and line.get("Exe") == 1.0 and all(map(ev.holds_at_end, ev.stated)) and (line.get("GCR") or 0) < 1:
            return GOAL_NOT_INSTRUCTION, f"stated goals all met; the benchmark's {_lines(missing)} not stated"
        # The task's own conditions are within the team's reach (the oracle reaches every feasible task), so
        # where the stated goal was found out of reach or its search ran out of time, what was added stood in
        # the way, whether or not the scene began with it.
        blocked = not ev.ran and (line.get("refused_by") in _REACH_CHECKS or _TIME_LIMIT in error)
        false_extra = [c for c in extra if blocked or not ev.holds_at_end(c)]
        if missing or false_extra:
            said = ([f"missed {_lines(missing)}"] if missing else []) + (
                [f"added {_lines(false_extra)}" + (", out of reach" if blocked else ", false at the end")]
            if false_extra else [])
            after = f" (refused by the {line.get('refused_by') or 'model'})" if line.get("refused") else ""
            return WRONG_GOAL, "; ".join(said) + after
    if line.get("refused") and line.get("refused_by") != "planner":
        return REFUSED, f"by {line.get('refused_by') or 'model'}"
    if not ev.ran and not error.startswith(_EXECUTION_ERROR):
        return NO_PLAN, "refused by the planner" if line.get("refused") else error or "no plan"
    if error or (line.get("Exe") or 0.0) < 1.0:
        return EXECUTION, error or f"Exe {line.get('Exe') or 0.0:.2f}"
    if (line.get("GCR") or 0.0) < 1.0:
        return SHORT, f"GCR {line.get('GCR') or 0.0:.2f} with every action succeeding"
    return EXTRA_WORK, f"RU {line.get('RU') or 0.0:.2f} with every goal condition met"


def _lines(conditions: Sequence[Condition]) -> str:
    return ", ".join(f"`{condition_line(c)}`" for c in conditions)


def run_failures(folder: str | Path) -> list[Failure]:
    """Classify every failed feasible task of the run in ``folder`` (one run, not a ``--seeds`` folder).

    Raises:
        UserError: the folder holds no readable run, or its task files can no longer be read.
    """
    folder = Path(folder)
    try:
        manifest = json.loads((folder / RUN_FILE).read_text(encoding="utf-8"))
        lines = list(read_results(folder / RESULTS).values())
    except (OSError, ValueError) as exc:
        raise UserError(f"cannot read the run in {folder}: {exc}") from exc
    arguments = manifest.get("identity", {}).get("arguments", {})
    domain = with_catalogue(load_domain(arguments.get("domain")), arguments.get("catalogue"))
    files = list(manifest.get("identity", {}).get("task_files", {})) or domain.task_files()
    try:
        tasks = {t.id: t for t in load_tasks(files, catalogue=domain.catalogue, domain=domain)}
    except SmartLLMError as exc:
        raise UserError(f"the tasks of the run in {folder} cannot be read ({exc}): a failure is judged against "
                        "them") from exc
    found: list[Failure] = []
    for line in lines:
        task = tasks.get(line["id"])
        if task is None or not task.feasible:
            continue
        ran = not line.get("refused") and not line.get("error") and "SR" in line
        ev = Evidence(line, ran, _stated(folder / task.id, domain), [c for g in task.goals for c in g.conditions()],
                      _lazy(lambda task=task, ran=ran: _end(folder / task.id, task, ran, domain)))
        kind = classify(ev)
        if kind is not None:
            found.append(Failure(task.id, task.category, *kind))
    return found


def _stated(task_folder: Path, domain: Domain) -> list[Condition] | None:
    """The goal stage's conditions with the steps' placements in their place (None where the stage did not run,
    refused, or wrote what does not parse)."""
    path = task_folder / "goals.txt"
    if not path.is_file():
        return None
    states = world_of(domain).task_rules().goal_states
    try:
        statement = parse_goal_statement(path.read_text(encoding="utf-8"), where=str(path), states=states)
    except PlanError:
        return None
    if statement.refusal is not None:
        return None
    record = task_folder / "allocation" / "record.json"
    try:
        placed = json.loads(record.read_text(encoding="utf-8")).get("placements") or [] if record.is_file() else []
        if not placed:
            return statement.conditions
        return merge(statement.conditions, parse_goal_statement("\n".join(placed), where=str(record),
                                                                states=states).conditions)
    except (OSError, ValueError, AttributeError, PlanError) as exc:
        raise UserError(f"{record}: the placements the goal-planner read cannot be read ({exc}): run the task "
                        "again (benchmark run resumes it) to judge its failure") from exc


def _lazy(end: Callable[[], list[dict[str, Any]]]) -> Callable[[Condition], bool]:
    """Whether a condition holds in the end state, computed (by a replay) at the first question only."""
    cache: dict[str, Any] = {}

    def holds(condition: Condition) -> bool:
        if "objects" not in cache:
            cache["objects"] = end()
            cache["inside"] = containment(cache["objects"])
        return condition_holds(condition, cache["objects"], cache["inside"])
    return holds


def _end(task_folder: Path, task: Task, ran: bool, domain: Domain) -> list[dict[str, Any]]:
    """The objects at the end of the task's run: its allocated plan replayed by the executor in process
    (the dry run's world, in which a call does what it does through a Controller), or the scene as it
    began where no plan ran."""
    team = domain.catalogue.team(task.robots)
    skills, world = domain.catalogue.skills, world_of(domain)
    if not ran:
        return list(world.dry_run(task.floor_plan, skills, team).objects)
    try:
        plan = read_plan(task_folder / "allocated.py", form="allocated", skills=skills, team_size=len(team),
                         scene_types=world.plan_types(task.floor_plan))
        return world.run_in_process(plan, task.floor_plan, team, skills).final_objects
    except SmartLLMError as exc:
        raise UserError(f"{task.id}: its plan ran in the benchmark but cannot be replayed to judge its failure "
                        f"({exc}): is {task_folder} the run's own?") from exc


__all__ = ["KINDS", "SHOWN", "Evidence", "Failure", "classify", "run_failures"]
