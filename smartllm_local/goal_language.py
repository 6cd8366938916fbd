"""Goal statements: what must hold when a task is done, one condition per line, in the scorer's terms.

The goal stage writes them; the benchmark's ground truth states the same things as JSON. The syntax
is small enough to read at a glance and to parse one way only::

    Apple in Fridge         an object of the first type inside one of the second (nested counts)
    Laptop on Bed           the same, for a thing on a surface ("on" and "in" both say what holds it)
    LightSwitch off         an object of the type in a state, written in lower case
    # INFEASIBLE: <why>     the one line of a refusal

A blank line ends a statement. Where the scene's types are known, a type may also be named by a word of
its name that no other type of the scene has (:func:`aliases`: ``Phone`` is the ``CellPhone``); a small
model that means the phone then writes it, rather than the first listed name the grammar lets it start.
Each line becomes one :class:`~smartllm_local.scoring.Goal` (``Apple in
Fridge`` is ``{"name": "Fridge", "contains": ["Apple"]}``, ``LightSwitch off`` is ``{"name":
"LightSwitch", "state": "OFF"}``), so a stated goal is scored by the scorer that scores the benchmark's.

Which states an object can be in is the world's knowledge (:func:`object_states`): the states whose test
in the scorer can ever pass for an object with its flags.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from .errors import PlanError
from .scoring import SITE_STATES, STATES, Condition, Goal

#: Every goal state, as a statement writes it.
STATE_WORDS: dict[str, str] = {state: state.lower() for state in (*STATES, *SITE_STATES)}
_WORD_STATES = {word: state for state, word in STATE_WORDS.items()}
#: States no object holds at once (a statement naming both for one type contradicts itself).
OPPOSITES: dict[str, str] = {"ON": "OFF", "OFF": "ON", "OPENED": "CLOSED", "CLOSED": "OPENED", "HOT": "COLD",
                             "COLD": "HOT", "CLEAN": "DIRTY", "DIRTY": "CLEAN"}
CONTAINMENT = " in "
#: The ways a statement may say that one thing holds another: in a receptacle, on a surface.
PREPOSITIONS = (CONTAINMENT, " on ")
_LINE = re.compile(r"^([A-Za-z][A-Za-z0-9]*)(?: (?:in|on) ([A-Za-z][A-Za-z0-9]*)| ([a-z]+))$")
_NAME_WORD = re.compile(r"[A-Z]+(?![a-z])|[A-Z]?[a-z]+")
#: The shortest word of a type's name that names it alone.
ALIAS_LETTERS = 3
_REFUSAL = re.compile(r"^#\s*INFEASIBLE\s*:\s*(.*?)\s*$")

#: An AI2-THOR object's flag that lets the world give it each state (see scoring's state tests).
_STATE_FLAGS: dict[str, tuple[str, ...]] = {
    "SLICED": ("sliceable",), "ON": ("toggleable",), "OFF": ("toggleable",), "OPENED": ("openable",),
    "CLOSED": ("openable",), "HOT": ("pickupable",), "COLD": ("pickupable",), "COOKED": ("cookable",),
    "BROKEN": ("breakable",), "PICKED": ("pickupable",), "CLEAN": ("dirtyable",), "DIRTY": ("dirtyable",),
    "FILLED": ("canFillWithLiquid",), "EMPTY": ("receptacle",),
}


def object_states(flags: Mapping[str, Any], object_type: str = "") -> frozenset[str]:
    """The states the AI2-THOR world can give an object with these flags. Only what is moved into a heat or
    cold source (a pickupable object) changes temperature; a StoveBurner is on or off with its knob."""
    states = {state for state, needed in _STATE_FLAGS.items() if any(flags.get(f) for f in needed)}
    if object_type == "StoveBurner":
        states |= {"ON", "OFF"}
    return frozenset(states)


@dataclass(frozen=True)
class GoalStatement:
    """A parsed statement: its goals, one per line, or the refusal it is."""

    goals: tuple[Goal, ...] = ()
    refusal: str | None = None

    @property
    def conditions(self) -> list[Condition]:
        """The conditions the scorer checks, each once, in the order stated."""
        return list(dict.fromkeys(c for g in self.goals for c in g.conditions()))

    def text(self) -> str:
        """The statement as the goal stage writes it."""
        if self.refusal is not None:
            return f"# INFEASIBLE: {self.refusal}\n"
        return "".join(condition_line(c) + "\n" for c in self.conditions)

    def as_dicts(self) -> list[dict[str, Any]]:
        """The goals in a task file's shape (``{"name", "contains", "state"}``)."""
        return [g.as_dict() for g in self.goals]


def condition_line(condition: Condition) -> str:
    """One condition as a statement writes it."""
    if condition.state is not None:
        return f"{condition.subject} {STATE_WORDS[condition.state]}"
    return f"{condition.item}{CONTAINMENT}{condition.subject}"


def statement_of(goals: Iterable[Goal]) -> GoalStatement:
    """A task's goals as a statement of one goal per condition (how the goal stage would state them)."""
    conditions = dict.fromkeys(c for g in goals for c in g.conditions())
    return GoalStatement(tuple(Goal(c.subject, state=c.state) if c.state else Goal(c.subject, contains=(c.item or "",))
                               for c in conditions))


def name_words(object_type: str) -> list[str]:
    """The words of a type's name as it is written (``CellPhone``: Cell, Phone; ``TVStand``: TV, Stand)."""
    return _NAME_WORD.findall(object_type)


def aliases(types: Iterable[str]) -> dict[str, str]:
    """Other names of the scene's types: each word of a type's name (``CellPhone``: Cell, Phone) that is a word
    of no other type's name and is not itself a type, capitalized, at least :data:`ALIAS_LETTERS` letters."""
    types = list(types)
    owners: dict[str, set[str]] = {}
    for kind in types:
        for word in name_words(kind):
            owners.setdefault(word.capitalize(), set()).add(kind)
    taken = {t.lower() for t in types}
    return {word: next(iter(kinds)) for word, kinds in sorted(owners.items())
            if len(kinds) == 1 and len(word) >= ALIAS_LETTERS and word.lower() not in taken}


def parse_goal_statement(text: str, *, where: str = "<goals>", states: Sequence[str] = tuple(STATE_WORDS),
                         types: Iterable[str] | None = None) -> GoalStatement:
    """Read a goal statement (the goal stage's output, or a file a person wrote).

    ``states``: those the domain's world knows; ``types``: the scene's object types (None: any name), each
    of which may also be named by one of its :func:`aliases`.

    Raises:
        PlanError: every line that is not a condition, naming its line and what is wrong.
    """
    known = None
    if types is not None:
        types = list(types)
        known = {alias.lower(): kind for alias, kind in aliases(types).items()} | {t.lower(): t for t in types}
    lines = text.splitlines()
    for number, line in enumerate(lines, start=1):
        refusal = _REFUSAL.match(line.strip())
        if refusal:
            others = [k for k, other in enumerate(lines, start=1) if other.strip() and k != number]
            if others:
                raise PlanError([(others[0], 1, "a refusal is the statement's only line")], where)
            return GoalStatement(refusal=refusal.group(1))
    goals: list[Goal] = []
    problems: list[tuple[int, int, str]] = []
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        match = _LINE.match(line.strip())
        if match is None:
            problems.append((number, 1, f"{line.strip()!r} is not a condition: write `Apple in Fridge` or "
                                        "`LightSwitch off`"))
            continue
        first, receptacle, word = match.groups()
        names = [first, receptacle] if receptacle else [first]
        unknown = [n for n in names if known is not None and n.lower() not in known]
        if unknown:
            problems.append((number, 1, f"{unknown[0]!r} is not an object of this scene"))
            continue
        if known is not None:
            names = [known[n.lower()] for n in names]
        if receptacle:
            goals.append(Goal(names[1], contains=(names[0],)))
        elif _WORD_STATES.get(word) in states:
            goals.append(Goal(names[0], state=_WORD_STATES[word]))
        else:
            words = ", ".join(STATE_WORDS[s] for s in states)
            problems.append((number, len(first) + 2, f"{word!r} is not a state; the states are {words}"))
    if problems:
        raise PlanError(problems, where)
    if not goals:
        raise PlanError([(1, 1, "no condition: a statement needs at least one line, or a refusal")], where)
    return GoalStatement(tuple(goals))
