"""Running hand-written plans through the real Controller, and reading what they did."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from typing import Any

from smartllm_local.domain import load_domain
from smartllm_local.executor import Execution, run_plan
from smartllm_local.plan_language import parse_plan
from smartllm_local.scoring import Scores, parse_goals, score_execution

CATALOGUE = load_domain().catalogue


def run(source: str, robots: Sequence[int], controller: Any, floor_plan: int | str = 6, **kwargs) -> Execution:
    """Parse an allocated plan (robots checked against the team) and run it on a reused Controller."""
    team = CATALOGUE.team(robots)
    plan = parse_plan(textwrap.dedent(source), team_size=len(team), skills=CATALOGUE.skills)
    return run_plan(plan, floor_plan, team, controller=controller, skills=CATALOGUE.skills, **kwargs)


def scores(execution: Execution, goals: list[dict] | None = None, **kwargs) -> Scores:
    return score_execution(execution, parse_goals(goals or []), **kwargs)


def objects_of(execution: Execution, object_type: str) -> list[dict[str, Any]]:
    return [o for o in execution.final_objects if o["objectType"] == object_type]


def one(execution: Execution, object_type: str) -> dict[str, Any]:
    (obj,) = objects_of(execution, object_type)
    return obj


def steps(execution: Execution) -> list[tuple[int, str, tuple[int, ...], bool]]:
    """(tick, skill, robot ids, success) per action: a compact view of the trace."""
    return [(e.tick, e.skill, tuple(e.robots), e.success) for e in execution.trace]


def agent_position(controller: Any, member: int) -> tuple[float, float]:
    pos = controller.last_event.events[member].metadata["agent"]["position"]
    return pos["x"], pos["z"]


_PER_AGENT = frozenset({"distance", "visible", "isInteractable"})


def run_record(execution: Execution) -> dict[str, Any]:
    """What a run did and left behind, without the fields that depend on which agent reported the scene."""
    objects = sorted(({k: v for k, v in o.items() if k not in _PER_AGENT} for o in execution.final_objects),
                     key=lambda o: o["objectId"])
    return {"trace": [e.as_dict() for e in execution.trace], "transitions": execution.transitions,
            "ticks": execution.ticks, "starts": execution.starts, "objects": objects}
