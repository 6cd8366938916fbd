"""Running plans: the interpreter (scheduler) and what skills do (team actions, the site simulator).

:func:`run_plan` opens (or reuses) a Controller for the plan's floor plan and
team, and executes; :func:`run_site_plan` runs a site domain's plan on its
simulated site. The scorer reads the :class:`Execution` either returns.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ..domain import Domain
from ..plan_language import Plan
from ..robots import Robot
from ..skills import DEFAULT_SKILL_SET, SkillSet
from ..world.controller import open_controller
from ..world.scenes import floor_plan_name
from .scheduler import DEFAULT_MAX_TICKS, Execution, TraceEntry, check_team, execute, run
from .site import SiteWorld

__all__ = ["Execution", "TraceEntry", "execute", "run_plan", "run_site_plan"]


def run_plan(
    plan: Plan,
    floor_plan: int | str,
    team: Sequence[Robot],
    *,
    controller: Any = None,
    build: str | None = None,
    skills: SkillSet = DEFAULT_SKILL_SET,
    max_ticks: int = DEFAULT_MAX_TICKS,
    object_filter: bool = True,
) -> Execution:
    """Execute ``plan`` on ``floor_plan`` with ``team`` (AI2-THOR's world: :class:`smartllm_local.worlds.Ai2ThorWorld`).

    A given ``controller`` is reset to the floor plan with one agent per robot
    and reused (much faster for many runs); otherwise one is opened and stopped.
    """
    scene = floor_plan_name(floor_plan)
    if controller is not None:
        controller.reset(scene, agentCount=len(team))
        return execute(plan, controller, team, skills=skills, max_ticks=max_ticks, object_filter=object_filter)
    controller = open_controller(scene, agent_count=len(team), build=build)
    try:
        return execute(plan, controller, team, skills=skills, max_ticks=max_ticks, object_filter=object_filter)
    finally:
        controller.stop()


def run_site_plan(plan: Plan, domain: Domain, team: Sequence[Robot], *,
                  max_ticks: int = DEFAULT_MAX_TICKS) -> Execution:
    """Execute ``plan`` with ``team`` on a site domain's simulated site (:mod:`.site`).

    Raises:
        UserError: the plan is decomposed or names robots outside the team.
    """
    check_team(plan, len(team))
    return run(plan, SiteWorld(domain, team), team, skills=domain.catalogue.skills, max_ticks=max_ticks)
