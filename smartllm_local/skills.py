"""The robots' skill vocabulary: SMART-LLM's fourteen skills and what each needs.

A skill is what a plan calls (``PickupObject(robot, 'Apple')``); it maps to an
AI2-THOR action (``PickupObject``) or, for ``GoToObject``, to navigation. Each
object argument must have an affordance (a metadata flag such as
``pickupable``): the planner's grammars admit only such objects, and the
executor picks instances that have it. Catalogue files may add skills that
map onto the same AI2-THOR actions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Mapping


@dataclass(frozen=True)
class Skill:
    """A skill and the shape of its call.

    Attributes:
        name: the name plans call.
        action: the AI2-THOR action it performs ("" for GoToObject, which navigates).
        arguments: the affordance each object argument needs ("" for any object);
            arguments past ``required`` are optional.
        required: how many object arguments every call must give.
    """

    name: str
    action: str
    arguments: tuple[str, ...]
    required: int

    @property
    def max_arguments(self) -> int:
        return len(self.arguments)


def _skill(name: str, action: str, *arguments: str, required: int | None = None) -> Skill:
    return Skill(name, action, tuple(arguments), len(arguments) if required is None else required)


#: SMART-LLM's skills, in the order its prompts list them.
DEFAULT_SKILLS: tuple[Skill, ...] = (
    _skill("GoToObject", "", ""),
    _skill("OpenObject", "OpenObject", "openable"),
    _skill("CloseObject", "CloseObject", "openable"),
    _skill("BreakObject", "BreakObject", "breakable"),
    _skill("SliceObject", "SliceObject", "sliceable"),
    _skill("SwitchOn", "ToggleObjectOn", "toggleable"),
    _skill("SwitchOff", "ToggleObjectOff", "toggleable"),
    _skill("CleanObject", "CleanObject", "dirtyable"),
    _skill("PickupObject", "PickupObject", "pickupable"),
    _skill("PutObject", "PutObject", "pickupable", "receptacle"),
    _skill("DropHandObject", "DropHandObject", "pickupable"),
    # LLM plans also write ThrowObject(robot, 'Fork', 'GarbageCan'): the target is optional.
    _skill("ThrowObject", "ThrowObject", "pickupable", "receptacle", required=1),
    _skill("PushObject", "PushObject", "movable"),
    _skill("PullObject", "PullObject", "movable"),
)

#: AI2-THOR actions a skill may be mapped onto by a catalogue.
THOR_ACTIONS = frozenset(s.action for s in DEFAULT_SKILLS if s.action) | {""}

#: Affordances a skill argument may require ("movable": moveable or pickupable).
AFFORDANCES = frozenset(
    {"", "pickupable", "receptacle", "openable", "toggleable", "sliceable", "breakable", "dirtyable", "movable"}
)


class SkillSet(Mapping[str, Skill]):
    """An ordered, read-only mapping of skill names to skills."""

    def __init__(self, skills: Iterable[Skill] = DEFAULT_SKILLS):
        self._skills = {s.name: s for s in skills}

    def __getitem__(self, name: str) -> Skill:
        return self._skills[name]

    def __iter__(self):
        return iter(self._skills)

    def __len__(self) -> int:
        return len(self._skills)

    def __repr__(self) -> str:
        return f"SkillSet({list(self._skills)})"


def has_affordance(obj: Mapping[str, object], affordance: str) -> bool:
    """Whether an AI2-THOR object (metadata dict) offers an affordance."""
    if not affordance:
        return True
    if affordance == "movable":
        return bool(obj.get("moveable") or obj.get("pickupable"))
    return bool(obj.get(affordance))


DEFAULT_SKILL_SET = SkillSet()
