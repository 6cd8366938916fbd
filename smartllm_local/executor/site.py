"""The site simulator: a domain's robots moving over a 2-D site, patrolling regions and photographing objects.

This is SMART-LLM's real-robot experiment in simulation. Every robot starts at the domain's ``start``
entry. A skill's effect (declared in the domain file) decides what a call does:

- ``move`` (GoToLocation): the robots go to the named location, region or object.
- ``photograph`` (ClickPicture): succeeds when one of the robots is within its ``camera_range`` of
  the object; the object counts as PHOTOGRAPHED.
- ``patrol`` (Patrol): the robots go to the region and sweep it together; the region counts as
  COVERED when their pooled capacity (the skill's ``pools``, e.g. visibility area) reaches its area.

A team acts with the union of its members' skills; a pooled capacity and a camera count the members
that have the skill. A place with ``reach`` can be entered only by robots of those kinds (a roof, by
aerial robots), and a team goes only where every member can. Each call takes one tick, as in AI2-THOR.
A call that fails changes nothing, and says why.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ..domain import ANY_KIND, Domain, Place, pooled
from ..robots import Robot
from ..scoring import SITE_STATES, Goal
from ..skills import Skill
from .team_actions import Outcome


class SiteWorld:
    """A run's site: where each robot is, which regions are covered and which objects photographed."""

    def __init__(self, domain: Domain, team: Sequence[Robot]):
        self.domain, self.team = domain, list(team)
        start = domain.places[domain.start]
        self.positions = [start.at for _ in self.team]
        self.covered: set[str] = set()
        self.photographed: set[str] = set()

    def perform_all(self, steps: Sequence[tuple[Skill, Sequence[str], Sequence[int]]]) -> list[Outcome]:
        outcomes = []
        for skill, objects, members in steps:
            outcome = self.perform(skill, objects, members)
            outcome.positions = [self.positions[m] for m in members]
            place = self.domain.places.get(outcome.object_id or "")
            outcome.object_position = place.at if place is not None else None
            outcomes.append(outcome)
        return outcomes

    def perform(self, skill: Skill, objects: Sequence[str], members: Sequence[int]) -> Outcome:
        """Carry out one call; a failure leaves the site as it was and says why."""
        effect = self.domain.effects[skill.name]
        place = self.domain.place(objects[0]) if objects else None
        robots = [self.team[m] for m in members]
        problem = why_not(self.domain, effect, skill.name, place, robots, objects[0] if objects else "")
        if not problem and effect == "photograph":
            problem = self._out_of_range(place, [m for m in members if skill.name in self.team[m].skills])  # type: ignore[arg-type]
        if problem:
            return Outcome(success=False, error=problem, action=skill.name)
        assert place is not None
        if effect in ("move", "patrol"):
            for m in members:
                self.positions[m] = place.at
        if effect == "patrol":
            self.covered.add(place.name)
        elif effect == "photograph":
            self.photographed.add(place.name)
        return Outcome(success=True, error="", action=skill.name, object_id=place.name)

    def _out_of_range(self, place: Place, members: Sequence[int]) -> str:
        nearest = min(members, key=lambda m: math.dist(self.positions[m], place.at))
        distance = math.dist(self.positions[nearest], place.at)
        robot = self.team[nearest]
        if any(math.dist(self.positions[m], place.at) <= self.team[m].capacity("camera_range") for m in members):
            return ""
        return (f"{place.name} is {distance:.0f} m from {robot.name}, beyond its camera_range of "
                f"{robot.capacity('camera_range'):g} m: go to it first")

    def release(self) -> None:
        pass

    @property
    def layout(self) -> dict[str, Any]:
        """The site for a map: no cells (it is open ground), the start, and every site entry as a landmark."""
        start = self.domain.places[self.domain.start].at
        return {"cells": [], "start": [list(start) for _ in self.team],
                "landmarks": [{"id": p.name, "type": p.kind, "x": p.at[0], "z": p.at[1]}
                              for p in self.domain.places.values()]}

    @property
    def objects(self) -> list[dict[str, Any]]:
        """Every site entry with its goal-state properties, in the shape the scorer reads."""
        def state(p: Place) -> dict[str, bool]:
            held = {"COVERED": p.name in self.covered, "PHOTOGRAPHED": p.name in self.photographed,
                    "RETURNED": all(at == p.at for at in self.positions)}
            return {SITE_STATES[name]: value for name, value in held.items()}

        return [{"objectType": p.name, "objectId": p.name, "kind": p.kind, **state(p)}
                for p in self.domain.places.values()]


NOTIONAL_CAMERA = 1e-6  # metres: the notional robot photographs only what it stands at


def notional_site_robot(domain: Domain) -> Robot:
    """A robot for the planner's dry runs of a site: every skill, of every kind (it reaches every place),
    unbounded capacities, and a camera that sees only what it stands at (a real robot's sees farther)."""
    capacities = {name: (NOTIONAL_CAMERA if name == "camera_range" else math.inf) for name in domain.capacities}
    return Robot(id=-1, name="notional robot", skills=frozenset(domain.catalogue.skills), mass_capacity=math.inf,
                 kind=ANY_KIND, capacities=tuple(sorted(capacities.items())))


class SiteDryRun:
    """A site that can branch, for the planner's world check: what :class:`SiteWorld` decides, tried
    and undone."""

    def __init__(self, domain: Domain, team: Sequence[Robot]):
        self.world = SiteWorld(domain, team)
        self.skills = domain.catalogue.skills

    def succeeds(self, members: Sequence[int], skill: str, objects: Sequence[str]) -> Outcome:
        saved = self.snapshot()
        try:
            return self.apply(members, skill, objects)
        finally:
            self.restore(saved)

    @property
    def objects(self) -> list[dict[str, Any]]:
        """The site's entries now, as the scorer reads a final state."""
        return self.world.objects

    def apply(self, members: Sequence[int], skill: str, objects: Sequence[str]) -> Outcome:
        return self.world.perform(self.skills[skill], objects, members)

    def snapshot(self) -> tuple:
        return list(self.world.positions), set(self.world.covered), set(self.world.photographed)

    def restore(self, saved: tuple) -> None:
        positions, covered, photographed = saved
        self.world.positions, self.world.covered, self.world.photographed = (
            list(positions), set(covered), set(photographed))


def why_not(domain: Domain, effect: str, skill: str, place: Place | None, robots: Sequence[Robot], name: str) -> str:
    """Why these robots cannot do this call anywhere on the site ("" if they can): the skill (some member
    must have it), the place, its kind, its reach (every member must get there), and for a patrol,
    whether the pooled capacity of the members with the skill covers the region."""
    if not any(skill in r.skills for r in robots):
        return f"{', '.join(r.name for r in robots)} cannot {skill}: no member has that skill"
    robots_with_skill = [r for r in robots if skill in r.skills]  # a team acts with its members' skills
    if place is None:
        return f"there is no {name!r} on the site {domain.site}"
    wanted = {"photograph": "object", "patrol": "region"}.get(effect)
    if wanted and place.kind != wanted:
        return f"{skill} takes {_a(wanted)}, and {place.name} is {_a(place.kind)}"
    barred = [r.name for r in robots if not place.reachable_by(r)]
    if barred:
        kinds = " or ".join(sorted(place.reach or ()))
        return f"{', '.join(barred)} cannot reach {place.name}: only {kinds} robots can"
    if effect == "photograph" and pooled(robots, skill, "camera_range") <= 0:
        return f"{', '.join(r.name for r in robots_with_skill)} has no camera (camera_range 0)"
    if effect == "patrol":
        capacity = domain.pools[skill]
        total = pooled(robots, skill, capacity)
        if total < place.area:
            return (f"{place.name} has an area of {place.area:g}; {', '.join(r.name for r in robots_with_skill)} "
                    f"pool {capacity} {total:g}: patrol it with a larger team")
    return ""


def unattainable(domain: Domain, goals: Sequence[Goal], team: Sequence[Robot]) -> list[str]:
    """The goal conditions no plan for this team can meet, each with why: a region the team cannot reach
    or cannot pool enough capacity to cover, an object no camera of the team can get within range of, a
    place some robot cannot get to. Sound, not complete: a condition named here is out of reach whatever
    the plan (a team call moves every member, so a robot goes wherever it and a member that moves can
    go). What an infeasible task must show, and what a planner may refuse on."""
    def effect_skills(effect: str) -> list[str]:
        return [s for s, e in domain.effects.items() if e == effect]

    movers = [(r, effect) for r in team for effect in ("move", "patrol") if set(effect_skills(effect)) & r.skills]
    start = domain.places[domain.start]

    def spots(robot: Robot) -> list[Place]:
        """Where the robot can be: the start, and every place it and some member that moves can get to."""
        return [start] + [p for p in domain.places.values() if p.reachable_by(robot) and any(
            p.reachable_by(m) and (effect == "move" or p.kind == "region") for m, effect in movers)]

    problems = []
    for goal in goals:
        place = domain.place(goal.name)
        if place is None:
            problems.append(f"there is no {goal.name!r} on the site {domain.site}")
            continue
        if goal.state == "COVERED":
            best = max((pooled(team, s, domain.pools[s], place) for s in effect_skills("patrol")), default=0.0)
            if best < place.area:
                problems.append(f"{place.name} COVERED: the team's robots that can patrol it pool {best:g}, "
                                f"less than its area {place.area:g}")
        elif goal.state == "PHOTOGRAPHED":
            cameras = [r for r in team if set(effect_skills("photograph")) & r.skills]
            if not any(math.dist(p.at, place.at) <= r.capacity("camera_range") for r in cameras for p in spots(r)):
                problems.append(f"{place.name} PHOTOGRAPHED: no robot of the team with a camera can get within "
                                "range of it")
        elif goal.state == "RETURNED":
            stuck = [r.name for r in team if not any(p.at == place.at for p in spots(r))]
            if stuck:
                problems.append(f"{place.name} RETURNED: {', '.join(stuck)} cannot get there")
    return problems


def _a(noun: str) -> str:
    return f"{'an' if noun[0] in 'aeiou' else 'a'} {noun}"
