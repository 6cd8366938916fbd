"""The world a plan runs in: the one interface each kind of world implements, and the two built in.

A domain names its kind of world (``world = "ai2thor"`` in domain.toml, or a site's tables) and
:func:`world_of` gives the :class:`World` for it. Everything above the executor (the planner, the
benchmark, the commands) asks the world, never which kind it is: the scene a prompt and a grammar see,
running a plan, the dry run the constraints try lines on, what the scorer reads, and which goals a team
can never meet, and what the commands and the task files ask (which scene a task is in, which options
apply). A new kind of world is a class with :class:`World`'s members, named in :data:`WORLDS`;
:func:`check_world` says which member it lacks (the tests run it on every kind).

- :class:`Ai2ThorWorld`: AI2-THOR's floor plans, run through the real ``ai2thor`` Controller.
- :class:`SimulatedSite`: a site domain's 2-D site, run on its simulator (:mod:`.executor.site`).
"""

from __future__ import annotations

import copy
import inspect
import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path
from typing import Any, Protocol

from .domain import AI2THOR, ARGUMENT_TYPES, DOMAIN_FILE, Domain, DomainError, load_domain
from .errors import UserError
from .executor import Execution, reach, run_plan, run_site_plan, site
from .executor.dry_run import DryRun, notional_robot
from .executor.scheduler import execute
from .executor.site import SiteDryRun, notional_site_robot
from .executor.team_actions import Outcome
from .goal_language import object_states
from .plan_language import Plan
from .resources import data_dir
from .robots import Robot, load_catalogue
from .scene import AFFORDANCE_NAMES, Demand, GoalTerms, GoalVocabulary, SceneObjects
from .scoring import SITE_STATES, STATES, Goal
from .skills import SkillSet, has_affordance
from .world.controller import open_controller
from .world.object_types import SLICE_RESULTS, TYPE_PROPERTIES
from .world.rules import refuses
from .world.scenes import VALID_RANGE_TEXT, floor_plan_name, load_scene

#: The commands' options about the world, which a world takes or refuses (:attr:`World.options`):
#: ``--floor-plan`` picks one of its scenes (a world without it has one place, every task on it),
#: ``--thor-build`` names the Unity build it runs in (checked before a model loads), ``--catalogue`` gives
#: it other robots from a JSON catalogue.
WORLD_OPTIONS = ("--floor-plan", "--thor-build", "--catalogue")


@dataclass(frozen=True)
class TaskRules:
    """What a task of a world's domains may say: the schema its line meets, the states its goal conditions (and
    a goal file's) may name, and whether an infeasible task may list no missing skills where some goal condition
    is one no plan for its team can meet (:meth:`World.unattainable` shows why)."""

    schema: Mapping[str, Any]  # JSON schema (domains/task.schema.json, or one made from it); not to be changed
    goal_states: tuple[str, ...]
    infeasible_by_goals: bool


class Trial(Protocol):
    """A world that can branch, for the planner's world check: a call tried (and undone) or applied."""

    def succeeds(self, members: Sequence[int], skill: str, objects: Sequence[str]) -> Outcome: ...
    def apply(self, members: Sequence[int], skill: str, objects: Sequence[str]) -> Outcome: ...
    def snapshot(self) -> Any: ...
    def restore(self, saved: Any) -> None: ...

    @property
    def objects(self) -> Sequence[Mapping[str, Any]]:
        """The objects now, as the scorer reads a final state."""


class World(Protocol):
    """The world a domain's plans run in. ``floor_plan`` is the task's (a world of one place ignores it)."""

    kind: str  # the domain file's world: ai2thor or site

    def scene(self, floor_plan: int | str) -> SceneObjects:
        """What the planner knows of where a task happens: the objects a prompt lists and a grammar admits."""

    def examples_dir(self) -> Path:
        """The worked examples the planner's prompts show (written on this world's scenes)."""

    def open(self, floor_plan: int | str, agents: int, build: str | None) -> Any:
        """A Controller that :meth:`run` may reuse from one task to the next (the caller stops it), or None
        where runs need none."""

    def run(self, plan: Plan, floor_plan: int | str, team: Sequence[Robot], *, skills: SkillSet,
            controller: Any = None, build: str | None = None) -> Execution:
        """Run an allocated plan with ``team``; the scorer reads the :class:`Execution` (its final objects)."""

    def run_in_process(self, plan: Plan, floor_plan: int | str, team: Sequence[Robot],
                       skills: SkillSet) -> Execution:
        """:meth:`run` with nothing outside the process, call for call the same (to judge a run afterwards)."""

    def dry_run(self, floor_plan: int | str, skills: SkillSet, robots: Sequence[Robot] | None = None,
                agents: int = 1) -> Trial:
        """The world check's dry run, with ``robots``, or else ``agents`` notional robots that have every skill."""

    def plan_types(self, floor_plan: int | str) -> set[str] | None:
        """The object names a plan read from a file must use, checked before it runs (None: the run judges
        them, as AI2-THOR resolves a type to an instance)."""

    def unattainable(self, goals: Sequence[Goal], team: Sequence[Robot], skills: SkillSet,
                     floor_plan: int | str) -> list[str]:
        """The goal conditions no plan of ``team`` can meet here, each with why (what a planner may refuse on)."""

    # What the planner asks: the world's rules, as its prompts state them and its grammars keep them.

    goto_acts: bool  # whether a move is an end in itself (a site's robots return to base), not only a way to act

    def describe(self, scene: SceneObjects, name: str) -> str:
        """One of ``scene``'s objects as a prompt lists it: a Python dict of what a plan must know of it."""

    def coalition_rules(self) -> str:
        """The coalition prompt's rules: what a robot can do alone and what a team pools (lifting, reach)."""

    def goal_terms(self) -> GoalTerms:
        """How a goal is put here, the same in every scene: what a condition names, and the states it may say."""

    def goal_vocabulary(self, floor_plan: int | str) -> GoalVocabulary:
        """What a goal may say in a scene: the states the world can give each object, and what it can hold."""

    def call_demand(self, skill: str, objects: Sequence[str]) -> Demand | None:
        """What a call asks of the robots that make it beyond the skill (None: nothing): where they must get
        to, and what capacity they must pool there."""

    # What the commands and the task files ask: where a task is, which options apply, what a task may say.

    options: frozenset[str]  # those of WORLD_OPTIONS it takes; a command refuses the others
    venue: str  # where its plans run, as the refusal of an option it does not take names it

    def scene_name(self, floor_plan: int | str | None) -> str:
        """The scene a task's ``floor_plan`` or a command's ``--floor-plan`` names; None (not given) names the
        one place of a world that takes no ``--floor-plan``.

        Raises:
            UserError: no such scene here (the message lists those there are).
        """

    def describe_world(self) -> str:
        """The world in a few words, as ``domain check`` reports a domain."""

    def task_rules(self) -> TaskRules:
        """What a task of this world's domains may say, which its task files and reference plans are checked by."""


class Ai2ThorWorld:
    """AI2-THOR's floor plans: scenes from AI2-THOR's object metadata, plans run on the ai2thor Controller."""

    kind = AI2THOR

    def scene(self, floor_plan: int | str) -> SceneObjects:
        """The object types of the floor plan, grouped by affordance. Pieces that only exist after slicing
        (``TomatoSliced``) are included for every sliceable type: a plan may slice, then handle the pieces."""
        name = floor_plan_name(floor_plan)
        masses, by_affordance = _floor_plan_objects(name)
        return SceneObjects(floor_plan=name, masses=dict(masses), by_affordance=dict(by_affordance), world=self)

    def examples_dir(self) -> Path:
        """Household's: every AI2-THOR domain's prompts show household's examples."""
        return load_domain().prompts_dir()

    def open(self, floor_plan: int | str, agents: int, build: str | None) -> Any:
        return open_controller(floor_plan, agent_count=agents, build=build)

    def run(self, plan: Plan, floor_plan: int | str, team: Sequence[Robot], *, skills: SkillSet,
            controller: Any = None, build: str | None = None) -> Execution:
        return run_plan(plan, floor_plan, team, controller=controller, build=build, skills=skills)

    def run_in_process(self, plan: Plan, floor_plan: int | str, team: Sequence[Robot],
                       skills: SkillSet) -> Execution:
        """On the dry run's world (in which a call does what it does through a Controller)."""
        return execute(plan, DryRun(floor_plan, team, skills).controller, team, skills=skills)

    def dry_run(self, floor_plan: int | str, skills: SkillSet, robots: Sequence[Robot] | None = None,
                agents: int = 1) -> DryRun:
        return DryRun(floor_plan, list(robots) if robots else [notional_robot(skills)] * max(1, agents), skills)

    def plan_types(self, floor_plan: int | str) -> set[str] | None:
        return None

    def unattainable(self, goals: Sequence[Goal], team: Sequence[Robot], skills: SkillSet,
                     floor_plan: int | str) -> list[str]:
        """What the team's skills cannot bring about from the scene's initial state (:mod:`.executor.reach`)."""
        conditions = list(dict.fromkeys(c for g in goals for c in g.conditions()))
        return reach.unattainable(conditions, team, skills, load_scene(floor_plan_name(floor_plan)))

    goto_acts = False  # a robot goes to an object to act on it

    def describe(self, scene: SceneObjects, name: str) -> str:
        """Its type and the heaviest instance's mass (what lifting it takes)."""
        return f"{{'name': '{name}', 'mass': {scene.masses[name]:g}}}"

    def coalition_rules(self) -> str:
        return HOUSEHOLD_COALITION_RULES

    def goal_terms(self) -> GoalTerms:
        """Objects, in any state the scorer knows, or in a receptacle."""
        return GoalTerms("object", True, STATES)

    def goal_vocabulary(self, floor_plan: int | str) -> GoalVocabulary:
        """The floor plan's objects' flags, and the slices they can be cut into."""
        return _floor_plan_vocabulary(floor_plan_name(floor_plan))

    def call_demand(self, skill: str, objects: Sequence[str]) -> Demand | None:
        """Nothing: where a robot must be and what it lifts, the executor judges (mass: :mod:`...feasibility`)."""
        return None

    options = frozenset(WORLD_OPTIONS)
    venue = "AI2-THOR's floor plans"

    def scene_name(self, floor_plan: int | str | None) -> str:
        """The iTHOR floor plan (``6``, ``"6"`` and ``"FloorPlan6"`` name ``FloorPlan6``); every task names one."""
        if floor_plan is None:
            raise UserError(f"no floor plan given: name one of {VALID_RANGE_TEXT}")
        return floor_plan_name(floor_plan)

    def describe_world(self) -> str:
        return "AI2-THOR's floor plans"

    def task_rules(self) -> TaskRules:
        """domains/task.schema.json: iTHOR floor plans by number, AI2-THOR's states; an infeasible task names
        the skills its team lacks (as SMART-LLM's infeasible tasks do)."""
        return TaskRules(_household_task_schema(), STATES, infeasible_by_goals=False)


@cache  # read once; every task line is checked against it
def _household_task_schema() -> dict[str, Any]:
    return json.loads((data_dir("domains") / "task.schema.json").read_text(encoding="utf-8"))


@cache  # a floor plan's objects never change; the planner and the task files ask for the same few again and again
def _floor_plan_objects(floor_plan: str) -> tuple[dict[str, float], dict[str, tuple[str, ...]]]:
    """A floor plan's types with the heaviest instance's mass, and its types by affordance ("": every type)."""
    masses: dict[str, float] = {}
    flags: dict[str, set[str]] = {}
    for obj in load_scene(floor_plan):
        kind = obj["objectType"]
        masses[kind] = round(max(masses.get(kind, 0.0), float(obj.get("mass") or 0.0)), 3)
        flags.setdefault(kind, set()).update(a for a in AFFORDANCE_NAMES if has_affordance(obj, a))
    for kind in list(masses):
        if kind in SLICE_RESULTS:
            piece, count = SLICE_RESULTS[kind]
            masses[piece] = round(masses[kind] / count, 3)
            flags[piece] = {a for a in AFFORDANCE_NAMES
                            if has_affordance({p: True for p in TYPE_PROPERTIES[piece]}, a)}
    by_affordance = {"": tuple(sorted(masses))}
    for affordance in AFFORDANCE_NAMES:
        by_affordance[affordance] = tuple(sorted(t for t, f in flags.items() if affordance in f))
    return masses, by_affordance


HOUSEHOLD_COALITION_RULES = """\
# For each sub-task of a plan, choose the robot, or the team of robots, that will do it.
# A robot can only use its own skills and lift up to its mass capacity; a team pools
# its members' skills and lifts the sum of their capacities. Reason before choosing: say
# what the sub-task needs (its skills, and the mass of what it lifts), which robots have
# those skills and that strength, and what is missing; only then, after "so", name the
# robot or team. Prefer a single robot when one can do the whole sub-task. If no robot or
# team can do a sub-task, answer with one line: # INFEASIBLE: <why>.
"""


@cache  # a floor plan's objects never change; a benchmark asks for the same few again and again
def _floor_plan_vocabulary(floor_plan: str) -> GoalVocabulary:
    of_type: dict[str, list[dict[str, Any]]] = {}
    for obj in load_scene(floor_plan):
        of_type.setdefault(obj["objectType"], []).append(obj)
    for whole in [t for t in of_type if t in SLICE_RESULTS]:
        piece = SLICE_RESULTS[whole][0]
        of_type.setdefault(piece, [{"objectType": piece, **{p: True for p in TYPE_PROPERTIES[piece]}}])
    flags = {t: {name: True for obj in objs for name, value in obj.items() if value is True}
             for t, objs in of_type.items()}
    states = {t: object_states(f, t) for t, f in flags.items()}
    receptacles = [t for t, f in flags.items() if "receptacle" in f]

    def can_hold(receptacle: str, item: str) -> bool:  # as the world lets some one of them hold some other
        return receptacle != item and any(refuses(o, r) is None for o in of_type[item] for r in of_type[receptacle])

    holders = {t: frozenset(r for r in receptacles if can_hold(r, t)) for t, f in flags.items() if "pickupable" in f}
    return GoalVocabulary(states, holders)


class SimulatedSite:
    """A site domain's one 2-D site: its entries are the objects, plans run on its simulator in process."""

    kind = "site"

    def __init__(self, domain: Domain):
        self.domain = domain
        self.venue = f"its site {domain.site}"

    def scene(self, floor_plan: int | str) -> SceneObjects:
        """The site's entries, grouped by the argument type each can fill (``place``: any entry); nothing is
        lifted, so every mass is 0. Every task is on the one site."""
        domain = self.domain
        by_type = {kind: tuple(sorted(p.name for p in domain.places.values() if kind in ("place", p.kind)))
                   for kind in ARGUMENT_TYPES}
        return SceneObjects(floor_plan=domain.site, masses={name: 0.0 for name in domain.places},
                            by_affordance={"": by_type["place"], **by_type}, world=self)

    def examples_dir(self) -> Path:
        return self.domain.prompts_dir()

    def open(self, floor_plan: int | str, agents: int, build: str | None) -> Any:
        return None

    def run(self, plan: Plan, floor_plan: int | str, team: Sequence[Robot], *, skills: SkillSet,
            controller: Any = None, build: str | None = None) -> Execution:
        """On the site simulator, with the domain's own skills (``skills``, ``controller`` and ``build`` are
        AI2-THOR's)."""
        return run_site_plan(plan, self.domain, team)

    def run_in_process(self, plan: Plan, floor_plan: int | str, team: Sequence[Robot],
                       skills: SkillSet) -> Execution:
        return run_site_plan(plan, self.domain, team)

    def dry_run(self, floor_plan: int | str, skills: SkillSet, robots: Sequence[Robot] | None = None,
                agents: int = 1) -> SiteDryRun:
        return SiteDryRun(self.domain, list(robots) if robots else [notional_site_robot(self.domain)] * max(1, agents))

    def plan_types(self, floor_plan: int | str) -> set[str] | None:
        return set(self.domain.places)

    def unattainable(self, goals: Sequence[Goal], team: Sequence[Robot], skills: SkillSet,
                     floor_plan: int | str) -> list[str]:
        return site.unattainable(self.domain, goals, team)

    goto_acts = True  # back to base is a step of its own

    def describe(self, scene: SceneObjects, name: str) -> str:
        """Its kind, a region's area (what a patrol pools) and, where only some kinds of robot get, which."""
        place = self.domain.places[name]
        area = f", 'area': {place.area:g}" if place.kind == "region" else ""
        reach = f", 'reach': {sorted(place.reach)!r}" if place.reach is not None else ""
        return f"{{'name': '{name}', 'kind': '{place.kind}'{area}{reach}}}"

    def coalition_rules(self) -> str:
        """A place's reach, and the capacities the domain's pooling skills add up."""
        pools = ", ".join(f"for {skill} their {capacity}" for skill, capacity in self.domain.pools.items())
        return f"""\
# For each sub-task of a plan, choose the robot, or the team of robots, that will do it.
# A robot can only use its own skills and go only where its kind may (a place's reach); a
# team pools its members' skills and adds up {pools}. Reason before choosing: say what the
# sub-task needs (its skills, what it pools, where only some robots go), which robots have
# that, and what is missing; only then, after "so", name the robot or team. Prefer a single
# robot when one can do the whole sub-task. If no robot or team can do a sub-task, answer
# with one line: # INFEASIBLE: <why>.
"""

    def goal_terms(self) -> GoalTerms:
        """Places, in the states the domain's skills can give them (nothing is put in anything)."""
        return GoalTerms("place", False, tuple(self.goal_vocabulary(self.domain.site).state_names()))

    def goal_vocabulary(self, floor_plan: int | str) -> GoalVocabulary:
        """A region covered, an object photographed, a location the team returns to, each where a skill of
        the domain has that effect."""
        effects = set(self.domain.effects.values())
        return GoalVocabulary({p.name: frozenset({SITE_GOALS[p.kind][1]}) for p in self.domain.places.values()
                               if SITE_GOALS[p.kind][0] in effects}, {})

    def call_demand(self, skill: str, objects: Sequence[str]) -> Demand | None:
        """A place's reach; a patrol pools the region's area, a photograph some camera."""
        domain = self.domain
        place = domain.place(objects[0]) if objects else None
        if place is None:
            return None
        if domain.effects.get(skill) == "patrol":
            return Demand(skill, place, domain.pools[skill], place.area)
        if domain.effects.get(skill) == "photograph":
            return Demand(skill, place, "camera_range", SOME_CAMERA)
        return Demand(skill, place) if place.reach is not None else None

    options: frozenset[str] = frozenset()  # one site (no floor plans), no Unity build, robots in the domain file

    def scene_name(self, floor_plan: int | str | None) -> str:
        """The one site, whatever is given (the task schema and the commands refuse any other name)."""
        return self.domain.site

    def describe_world(self) -> str:
        return f"{len(self.domain.places)} site entries on {self.domain.site}"

    def task_rules(self) -> TaskRules:
        """Household's schema, but ``floor_plan`` names the site and goals use the site's states; an infeasible
        task may list no missing skills (the site shows why it is infeasible)."""
        states = tuple(SITE_STATES)
        schema = copy.deepcopy(_household_task_schema())
        del schema["then"]["properties"]["missing_skills"]["minItems"]
        schema["properties"]["floor_plan"] = {"const": self.domain.site}
        schema["properties"]["goals"]["items"]["properties"]["state"] = {"enum": [None, *states]}
        return TaskRules(schema, states, infeasible_by_goals=True)


#: A site entry's kind, the effect a skill must have for the world to give it a state, and that state.
SITE_GOALS = {"region": ("patrol", "COVERED"), "object": ("photograph", "PHOTOGRAPHED"),
              "location": ("move", "RETURNED")}
SOME_CAMERA = 1e-3  # metres: a photograph needs a robot with some camera (how far it sees, the world check asks)


def scene_objects(floor_plan: int | str) -> SceneObjects:
    """An AI2-THOR floor plan's scene (:meth:`Ai2ThorWorld.scene`), for callers that only know AI2-THOR."""
    return Ai2ThorWorld().scene(floor_plan)


#: Each kind of world (a domain's ``world``), and how a domain's world of that kind is made.
WORLDS: dict[str, Callable[[Domain], World]] = {
    AI2THOR: lambda domain: Ai2ThorWorld(),
    "site": SimulatedSite,
}

#: The members a world has: a method with the arguments it is called with (positional names, then keywords),
#: or an attribute with its type.
MEMBERS: dict[str, tuple[str, ...] | type] = {
    "kind": str,
    "scene": ("floor_plan",),
    "examples_dir": (),
    "open": ("floor_plan", "agents", "build"),
    "run": ("plan", "floor_plan", "team", "*skills", "*controller", "*build"),
    "run_in_process": ("plan", "floor_plan", "team", "skills"),
    "dry_run": ("floor_plan", "skills", "robots", "agents"),
    "plan_types": ("floor_plan",),
    "unattainable": ("goals", "team", "skills", "floor_plan"),
    "goto_acts": bool,
    "describe": ("scene", "name"),
    "coalition_rules": (),
    "goal_terms": (),
    "goal_vocabulary": ("floor_plan",),
    "call_demand": ("skill", "objects"),
    "options": frozenset,
    "venue": str,
    "scene_name": ("floor_plan",),
    "describe_world": (),
    "task_rules": (),
}


def check_world(world: Any) -> World:
    """``world`` itself if it has every member of :class:`World`, taking the arguments it is called with.

    Raises:
        TypeError: a member is missing, is not a method, or does not take those arguments (says which).
    """
    name = type(world).__name__
    problems = []
    for member, arguments in MEMBERS.items():
        value = getattr(world, member, None)
        if value is None:
            problems.append(f"it has no {member}")
        elif arguments is str:
            if not isinstance(value, str) or not value:
                problems.append(f"{member} must be a name (a str), not {value!r}")
        elif isinstance(arguments, type):
            if not isinstance(value, arguments):
                problems.append(f"{member} must be a {arguments.__name__}, not {value!r}")
            elif member == "options" and not value <= set(WORLD_OPTIONS):
                problems.append(f"options may only name {', '.join(WORLD_OPTIONS)}, not "
                                f"{', '.join(sorted(value - set(WORLD_OPTIONS)))}")
        elif not callable(value):
            problems.append(f"{member} must be a method")
        else:
            args = [a for a in arguments if not a.startswith("*")]
            kwargs = {a[1:]: None for a in arguments if a.startswith("*")}
            try:
                inspect.signature(value).bind(*args, **kwargs)
            except TypeError as exc:
                problems.append(f"{member} must take ({', '.join(a.lstrip('*') for a in arguments)}): {exc}")
    if problems:
        raise TypeError(f"{name} is not a World: {'; '.join(problems)}. A kind of world implements every member "
                        "of smartllm_local.worlds.World (see docs/architecture.md, \"Kinds of world\").")
    return world


def world_of(domain: Domain) -> World:
    """The world the domain's plans run in.

    Raises:
        TypeError: no kind of world is named ``domain.world`` (the domain file's check only lets known kinds by).
    """
    make = WORLDS.get(domain.world)
    if make is None:
        raise TypeError(f"the {domain.name} domain's world is {domain.world!r}, which no kind of world in "
                        f"smartllm_local.worlds.WORLDS implements ({', '.join(WORLDS)})")
    return check_world(make(domain))


def with_catalogue(domain: Domain, catalogue: str | Path | None) -> Domain:
    """``domain`` with the robots of a JSON robot catalogue (``--catalogue``), where its world takes one; None
    leaves it as it is.

    Raises:
        DomainError: its world takes no catalogue (its robots are in its domain file).
        CatalogueError: the catalogue cannot be read or is not a catalogue.
    """
    if catalogue is None:
        return domain
    if "--catalogue" not in world_of(domain).options:
        raise DomainError(f"--catalogue gives an AI2-THOR domain other robots; the {domain.name} domain's robots "
                          f"are in its {DOMAIN_FILE}")
    return replace(domain, catalogue=load_catalogue(catalogue))
