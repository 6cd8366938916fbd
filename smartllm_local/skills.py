"""The robots' skill vocabulary: what a skill is, and the AI2-THOR actions and affordances skills map onto.

A skill is what a plan calls (``PickupObject(robot, 'Apple')``). In an AI2-THOR domain it performs an
AI2-THOR action (``PickupObject``) or navigates (``GoToObject``), and each object argument needs an
affordance (a metadata flag such as ``pickupable``): the planner's grammars admit only such objects, and
the executor picks instances that have it. SMART-LLM's fourteen skills are the household domain's, read
from ``domains/household/domain.toml``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from .resources import data_dir


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


#: The AI2-THOR actions the executor performs ("" is navigation: a skill with ``effect = "move"``).
THOR_ACTIONS = frozenset({"", "OpenObject", "CloseObject", "BreakObject", "SliceObject", "ToggleObjectOn",
                          "ToggleObjectOff", "CleanObject", "PickupObject", "PutObject", "DropHandObject",
                          "ThrowObject", "PushObject", "PullObject"})

#: Affordances a skill argument may require ("movable": moveable or pickupable).
AFFORDANCES = frozenset(
    {"", "pickupable", "receptacle", "openable", "toggleable", "sliceable", "breakable", "dirtyable", "movable"}
)


def thor_skill(name: str, entry: Mapping[str, Any]) -> Skill | list[str]:
    """An AI2-THOR domain's ``[skills.NAME]`` table as a skill, or what is wrong with it (each problem
    with its fix), so the domain reader and :data:`DEFAULT_SKILLS` read skills one way."""
    problems = [f"skill {name}: unknown key {key!r}; an AI2-THOR skill has action (or effect = \"move\"), "
                "arguments, required and description" for key in sorted(set(entry) - _THOR_SKILL_KEYS)]
    if not name.isidentifier():
        problems.append(f"skill {name!r} must be a Python identifier (plans call it)")
    if entry.get("effect") == "move" and "action" not in entry:
        action = ""
    elif "effect" in entry:
        return problems + [f'skill {name}: in AI2-THOR a skill moves (effect = "move") or names an action, '
                           f"not effect = {entry['effect']!r}"]
    else:
        action = entry.get("action")
        if not isinstance(action, str) or action not in THOR_ACTIONS - {""}:
            return problems + [f"skill {name}: action must be one of the AI2-THOR actions "
                               f"{', '.join(sorted(THOR_ACTIONS - {''}))}, got {action!r}"]
    arguments = entry.get("arguments", [""])
    if not (isinstance(arguments, list) and 1 <= len(arguments) <= 2
            and all(isinstance(a, str) and a in AFFORDANCES for a in arguments)):
        return problems + [f"skill {name}: arguments must list 1 or 2 affordances (\"\" for any object) from "
                           f"{', '.join(repr(a) for a in sorted(AFFORDANCES))}"]
    required = entry.get("required", len(arguments))
    if not isinstance(required, int) or isinstance(required, bool) or not 1 <= required <= len(arguments):
        problems.append(f"skill {name}: required is how many arguments every call gives, 1 to {len(arguments)}")
    return problems or Skill(name, action, tuple(arguments), required)


_THOR_SKILL_KEYS = {"action", "effect", "arguments", "required", "description"}


def _household_skills() -> tuple[Skill, ...]:
    """The household domain file's skills (SMART-LLM's fourteen), read where the domain ships."""
    path = data_dir("domains") / "household" / "domain.toml"
    skills = []
    for name, entry in tomllib.loads(path.read_text(encoding="utf-8"))["skills"].items():
        skill = thor_skill(name, entry)
        if isinstance(skill, list):
            raise RuntimeError(f"{path}: {'; '.join(skill)}: run `smartllm-local domain check household`")
        skills.append(skill)
    return tuple(skills)


#: SMART-LLM's skills, in the order its prompts list them: the household domain's.
DEFAULT_SKILLS: tuple[Skill, ...] = _household_skills()


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

    @property
    def lifting(self) -> frozenset[str]:
        """The skills that pick a thing up: a call of one weighs what it lifts."""
        return frozenset(s.name for s in self._skills.values() if s.action == "PickupObject")


def has_affordance(obj: Mapping[str, object], affordance: str) -> bool:
    """Whether an AI2-THOR object (metadata dict) offers an affordance."""
    if not affordance:
        return True
    if affordance == "movable":
        return bool(obj.get("moveable") or obj.get("pickupable"))
    return bool(obj.get(affordance))


DEFAULT_SKILL_SET = SkillSet()
