"""The goal stage's constraint: conditions over the scene's own objects, in states the world can give them.

Each line is a condition (see :mod:`smartllm_local.goal_language`): ``<Type> <state>`` offers only the states the
world can give that type in this scene (a LightSwitch on or off, never sliced), and ``<Item> in <Receptacle>`` (or
``on``) only receptacles the world lets hold the item (a Toaster only bread slices, a StoveBurner only cookware, a
cup nothing bigger than itself, nothing in itself). A type may be named by its name or by one of its aliases (a word
of its name no other type of the scene has: ``Phone``), so that where the model starts the name it means, the
grammar does not make it finish another (``P`` of "Phone" finished as ``Pen``). A condition already stated, or one
that contradicts it (``on`` after ``off``; ``Desk empty`` and ``Pen in Desk``, in either order), is not offered
again, so a statement never repeats or contradicts itself. A thing may be said to be in two holders, since holders
nest (a ball in the Bed is in the Floor too), but in no more (the 1.5B once listed the remote control in eight
holders and never ended). A blank line ends the statement after at least one condition; the first line may instead
be a refusal. At most :data:`MAX_GOALS` conditions, the lines owed among them.

A state the instruction asks for in so many words (``asked``: "fry the potato", COOKED) that the model ends its
statement without is owed: after the blank line comes a line of that state, then a blank line again. Its thing is
the model's choice among those the asking words name ("the potato") that the world can give the state, or where they
name none ("boil some water"), among those the statement speaks of that it can, else all the scene's; where they
name several each by a name of its own (``each``: "slice the apple, the lettuce and the tomato"), each is owed a
line. A small model
states where the potato goes and forgets that it must be cooked; the plan is then made for the goals stated. The
goal stage puts the owed lines first in the statement it keeps: where no plan meets every goal, the planner meets
the first it can. Where the asking words name some things, the state is not offered of any other thing in the
model's own lines either (asked to warm the potato, the 0.5B stated the tomato hot). A state the domain offers only
where asked for (``withheld`` otherwise: household's empty, which no goal example states and the small models stated
of the fridge they were to put the apple in) is not offered at all.

A holder the instruction asks things into in so many words (``placed``: "throw the cloth away", the GarbageCan) is
owed the same way: a line puts each thing the asking words name there (where they name none, "throw it away", one
thing of the model's choice), and a thing so named is offered in no other holder (asked to throw the cloth away, the
0.5B stated it in the sink), nor is the whole thing of a piece so named (asked to fry an egg, owed the cracked egg
in the pan, the 1.5B put the whole egg in the microwave too: dev13-p1). Owed placements come before owed states,
so that a state owed of nothing named goes to the thing just placed ("make me a coffee": the Mug in the CoffeeMachine
is filled, not the Cup).
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from itertools import count

from ...goal_language import CONTAINMENT, OPPOSITES, PREPOSITIONS, STATE_WORDS, aliases, parse_goal_statement
from ...scene import GoalVocabulary, SceneObjects
from ...scoring import Condition
from ...world.object_types import base_type
from ..decoding.grammar import Node, Ref, alt, seq
from ..decoding.protocol import Choose, Constraint, longest
from .format import refusal_line

MAX_GOALS = 8
MAX_HOLDERS = 2  # holders one thing may be said to be in
PICKED = "PICKED"
EMPTY = "EMPTY"


def goal_vocabulary(scene: SceneObjects) -> GoalVocabulary:
    """What a goal may say in ``scene``: the states and holders its world gives the scene's objects."""
    return scene.world.goal_vocabulary(scene.floor_plan)


class GoalConstraint(Constraint):
    """The goal stage: conditions, one a line, then a blank line (or one refusal line)."""

    def __init__(self, vocabulary: GoalVocabulary, *, allow_refusal: bool = True, max_goals: int = MAX_GOALS,
                 asked: Mapping[str, Sequence[str]] | None = None, withheld: Collection[str] = (),
                 placed: Mapping[str, Sequence[str]] | None = None, each: Mapping[str, Sequence[str]] | None = None):
        super().__init__()
        self.vocabulary, self.allow_refusal, self.max_goals = vocabulary, allow_refusal, max_goals
        self.withheld = frozenset(withheld)  # states not offered (not asked for, and offered only where asked)
        able = {state for states in vocabulary.states.values() for state in states}
        # A state nothing here can be in asks for nothing; a thing named that cannot be in it is not named for it.
        self.asked = {state: [kind for kind in named if state in vocabulary.states.get(kind, ())]
                      for state, named in (asked or {}).items() if state in able}
        self.each = {state: [kind for kind in named if kind in self.asked[state]]
                     for state, named in (each or {}).items() if state in self.asked}
        # A holder nothing here can go in asks for nothing; a thing named that cannot go in it is not named for it.
        receptacles = vocabulary.holder_types()
        self.placed = {holder: [kind for kind in named if holder in vocabulary.holders.get(kind, ())]
                       for holder, named in (placed or {}).items() if holder in receptacles}
        self.owing = False  # the model ended its statement; the states asked that it left out follow
        self.owed: list[Condition] = []  # the conditions written for them
        self.said: list[Condition] = []
        self.names: dict[str, list[str]] = {kind: [kind] for kind in vocabulary.types}
        for alias, kind in aliases(vocabulary.types).items():
            self.names[kind].append(alias)
        self.ended = False
        first, rules = self._conditions()
        self.must_refuse = first is None  # the scene offers nothing a goal could say
        self.longest_line = 0 if first is None else longest(first, rules)
        self.refusal_len = longest(refusal_line(), {})

    def minimum_budget(self) -> int:
        if self.must_refuse:
            return self.refusal_len
        return self.longest_line + 1  # the longest condition, then the blank line that ends the statement

    def next(self, remaining: int) -> Choose | None:
        if self.ended or self.refusal is not None or len(self.said) == self.max_goals:
            return None
        if self.owing:
            return self._owed(remaining)
        if self.said and len(self.said) + len(self._missing()) + len(self._unplaced()) >= self.max_goals:
            return self._choose({}, {"end": "\n"})  # the rest of the room is the owed lines'
        options: dict[str, Node] = {}
        if not self.said and (self.allow_refusal or self.must_refuse) and self.refusal_len <= remaining:
            options["refusal"] = refusal_line()
        condition, rules = self._conditions()
        # A condition only where the blank line that ends the statement still fits after it.
        if condition is not None and longest(condition, rules) + 1 <= remaining:
            options["condition"] = condition
        if self.said:
            options["end"] = "\n"
        return self._choose(rules, options)

    def _advance(self, kind: str, piece: str) -> None:
        if kind in ("condition", "owed"):
            said = parse_goal_statement(piece, types=self.vocabulary.types).conditions
            self.said.extend(said)
            self.owed.extend(said if kind == "owed" else ())
        elif kind == "end":
            self.ended = self.owing or not (self._missing() or self._unplaced())
            self.owing = not self.ended

    def _missing(self) -> list[tuple[str, list[str]]]:
        """The states asked for that no condition said so far states, each with the things one of which is owed it
        (none: any), and one for each of the things owed a state each that no condition states it of."""
        said = {(c.subject, c.state) for c in self.said}
        states = {state for _, state in said}
        missing = []
        for state, named in self.asked.items():
            if state in self.each:
                missing += [(state, [kind]) for kind in self.each[state] if (kind, state) not in said]
            elif state not in states:
                missing.append((state, named))
        return missing

    def _unplaced(self) -> list[tuple[str, list[str]]]:
        """The placements asked for that no condition said so far makes: (holder, the things one of which goes
        there), one for each thing named and not yet in it, or one where none is named and nothing is in it."""
        said_in, emptied, held = self._said_in(), self._emptied(), self._held()
        owed = []
        for holder, named in self.placed.items():
            if holder in emptied:  # said to hold nothing: a line putting a thing in it would contradict that
                continue
            if named:
                owed += [(holder, [kind]) for kind in named if holder not in said_in.get(kind, ())]
            elif not any(holder in holders for holders in said_in.values()):
                owed.append((holder, [k for k in self.vocabulary.types if holder in self.vocabulary.holders.get(k, ())
                                      and len(said_in.get(k, ())) < MAX_HOLDERS and k not in held]))
        return owed

    def _said_in(self) -> dict[str, set[str]]:
        """Each thing said to be in holders, with those holders."""
        said_in: dict[str, set[str]] = {}
        for c in self.said:
            if c.state is None:
                said_in.setdefault(c.item or "", set()).add(c.subject)
        return said_in

    def _emptied(self) -> set[str]:
        """The holders said to be empty: nothing may be said to be in them."""
        return {c.subject for c in self.said if c.state == EMPTY}

    def _owed(self, remaining: int) -> Choose | None:
        """A line of a placement asked for and left out, once none is left a state's (where one still fits), else
        the blank line that ends. A state's thing is one the asking words name, else one the statement speaks of
        ("make me a coffee": the Mug put in the coffee machine is filled, not the cup), else any."""
        lines = []
        for holder, kinds in self._unplaced():
            names = [name for kind in kinds for name in self.names[kind]]
            if names:
                lines.append(seq(alt(*names), CONTAINMENT, alt(*self.names[holder]), "\n"))
        closed = self._closed_states()
        for state, named in [] if lines else self._missing():
            able = [kind for kind in self.vocabulary.types if state in self.vocabulary.states.get(kind, ())
                    and state not in closed.get(kind, ())]
            spoken = {kind for c in self.said for kind in (c.subject, c.item)}
            kinds = [kind for kind in able if kind in named] if named else \
                [kind for kind in able if kind in spoken] or able
            names = [name for kind in kinds for name in self.names[kind]]
            if names:
                lines.append(seq(alt(*names), f" {STATE_WORDS[state]}\n"))
        options: dict[str, Node] = {"end": "\n"}
        if lines and longest(alt(*lines), {}) + 1 <= remaining:
            options = {"owed": alt(*lines)}
        return self._choose({}, options)

    def _closed_states(self) -> dict[str, set[str]]:
        """Each type's states no longer offered: those said of it and their opposites, the opposite of a state the
        asking words ask of it (not asked too: "open the fridge ... and close it"; "the bed is dirty; give it a clean":
        the 1.5B stated the bed dirty, dev6-e2), empty for a holder said to hold a thing, and picked (held by a
        robot, so in no holder) for a thing said or owed to be in one."""
        closed: dict[str, set[str]] = {kind: {PICKED} for named in self.placed.values() for kind in named}
        for state, named in self.asked.items():
            for kind in named:
                if OPPOSITES.get(state) and kind not in self.asked.get(OPPOSITES[state], ()):
                    closed.setdefault(kind, set()).add(OPPOSITES[state])
        for c in self.said:
            if c.state is not None:
                closed.setdefault(c.subject, set()).update({c.state, OPPOSITES.get(c.state, c.state)})
            else:
                closed.setdefault(c.subject, set()).add(EMPTY)  # a holder with a thing in it is not empty
                closed.setdefault(c.item or "", set()).add(PICKED)
        return closed

    def _held(self) -> set[str]:
        """The things said to be picked: held by a robot at the end, so in no holder."""
        return {c.subject for c in self.said if c.state == PICKED}

    def _asked_of_others(self, kind: str) -> set[str]:
        """The states asked for of things the asking words name, where ``kind`` is not one of them ("warm the
        potato": hot of the Potato, not of the Tomato)."""
        return {state for state, named in self.asked.items() if named and kind not in named}

    def _conditions(self) -> tuple[Node | None, dict[str, Node]]:
        """A condition line of those still to be said (None: none), and the rules it refers to. Types that
        may be followed by the same things share a rule."""
        said_states, said_in, emptied, held = self._closed_states(), self._said_in(), self._emptied(), self._held()
        groups: dict[tuple[frozenset[str], frozenset[str]], list[str]] = {}
        for kind in self.vocabulary.types:
            states = self.vocabulary.states.get(kind, frozenset()) - said_states.get(kind, set()) - \
                self._asked_of_others(kind) - self.withheld
            holders = self.vocabulary.holders.get(kind, frozenset()) - said_in.get(kind, set()) - emptied \
                if len(said_in.get(kind, ())) < MAX_HOLDERS and kind not in held else frozenset()
            asked_into = {holder for holder, named in self.placed.items()
                          if kind in named or any(base_type(n) == kind != n for n in named)}
            holders = holders & asked_into if asked_into else holders  # "throw the cloth away": only the bin
            if states or holders:
                groups.setdefault((frozenset(states), frozenset(holders)), []).append(kind)
        rules: dict[str, Node] = {}
        holder_rules: dict[frozenset[str], str] = {}
        lines = []
        numbers = count(1)
        for (states, holders), kinds in groups.items():
            rule = f"types-{next(numbers)}"
            rules[rule] = alt(*(name for kind in kinds for name in self.names[kind]))
            after: list[Node] = [seq(" ", alt(*(STATE_WORDS[s] for s in STATE_WORDS if s in states)))] if states else []
            if holders:
                name = holder_rules.setdefault(holders, f"holders-{len(holder_rules) + 1}")
                rules[name] = alt(*(n for kind in sorted(holders) for n in self.names[kind]))
                after.append(seq(alt(*PREPOSITIONS), Ref(name)))
            lines.append(seq(Ref(rule), alt(*after), "\n"))
        return (alt(*lines) if lines else None), rules
