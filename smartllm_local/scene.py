"""What the planner knows of where a task happens: its object types, their masses and affordances (or a site's
entries), and the terms the world answers the planner's questions in.

Prompts list the types (with the heaviest instance's mass) and grammars only admit, for each skill argument,
the types that offer what the skill needs. A world builds its scenes (:meth:`.worlds.World.scene`) and gives
the rest: what a goal may say (:class:`GoalVocabulary`, :class:`GoalTerms`) and what a call asks of the robots
that make it (:class:`Demand`). This module sits below both the prompts and the constraints, so each reads a
scene without importing the other, and below the worlds, which build these.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from .domain import Place, pooled
from .goal_language import STATE_WORDS
from .robots import Robot

if TYPE_CHECKING:  # the worlds build scenes, so they import this module
    from .worlds import World

AFFORDANCE_NAMES = ("pickupable", "receptacle", "openable", "toggleable", "sliceable", "breakable", "dirtyable",
                    "movable")
MASS_TOLERANCE = 1e-6  # scene masses are float32


@dataclass(frozen=True)
class SceneObjects:
    floor_plan: str
    masses: dict[str, float]  # type -> heaviest instance (kg)
    by_affordance: dict[str, tuple[str, ...]]  # affordance ("" = any) -> types, sorted
    world: World = field(compare=False, repr=False)  # the world it is a scene of (its dry runs, its examples' scenes)

    @property
    def types(self) -> tuple[str, ...]:
        return self.by_affordance[""]

    def types_for(self, affordance: str) -> tuple[str, ...]:
        return self.by_affordance.get(affordance, ())

    def python_list(self, only: Iterable[str] | None = None) -> str:
        """The objects as a Python list of dicts, as the prompts show them (each as its world describes it)."""
        chosen = self.types if only is None else [t for t in self.types if t in set(only)]
        items = ", ".join(self.world.describe(self, t) for t in chosen)
        return f"[{items}]"


@dataclass(frozen=True)
class GoalVocabulary:
    """What a goal may say about a scene: each type's states, and the receptacles each type can be put in."""

    states: Mapping[str, frozenset[str]]
    holders: Mapping[str, frozenset[str]]

    @property
    def types(self) -> tuple[str, ...]:
        named = set(self.states) | set(self.holders)
        return tuple(sorted(t for t in named if self.states.get(t) or self.holders.get(t)))

    def less(self, types: Collection[str]) -> GoalVocabulary:
        """The vocabulary without ``types``, as things or as holders."""
        return GoalVocabulary({t: s for t, s in self.states.items() if t not in types},
                              {t: h - set(types) for t, h in self.holders.items() if t not in types})

    def holder_types(self) -> frozenset[str]:
        """The receptacles any type of the scene can be put in."""
        return frozenset().union(*self.holders.values())

    def state_names(self) -> list[str]:
        """The states any type of the scene can be in, in the scorer's order."""
        present = set().union(*self.states.values()) if self.states else set()
        return [s for s in STATE_WORDS if s in present]


@dataclass(frozen=True)
class GoalTerms:
    """How a world's goals are put, the same in every scene (so the goal prompt's examples stay a shared
    prefix): what a condition names (``object``, ``place``), whether a goal may say what is in what, and the
    states a goal may name (in the scorer's order)."""

    thing: str
    containment: bool
    states: tuple[str, ...]


@dataclass(frozen=True)
class Demand:
    """What one call asks of the robots that make it beyond its skill: to get to ``place`` (its reach), and
    for a pooling skill, ``amount`` of ``capacity`` from the members that have ``skill`` and get there (a
    camera: some camera_range)."""

    skill: str
    place: Place
    capacity: str = ""
    amount: float = 0.0

    def met_by(self, robots: Sequence[Robot]) -> bool:
        able = [r for r in robots if self.skill in r.skills and self.place.reachable_by(r)]
        return bool(able) and (not self.capacity or pooled(able, self.skill, self.capacity)
                               + MASS_TOLERANCE >= self.amount)
