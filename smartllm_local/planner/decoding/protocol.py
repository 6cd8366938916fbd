"""Each stage's output, written one line at a time, every line drawn from a grammar.

A plan has cross-references a context-free grammar cannot express (the
orchestration names functions defined earlier; a thread's robot list must be
long enough for the indices its function uses). So a stage's constraint is a
small state machine: at each point it offers a GBNF grammar for the next line
(built from the scene's object types by affordance, the skills, the team and
what was written so far), or writes boilerplate itself (forced text). The
grammar of a stage is the composition of these line grammars.

Every line grammar is bounded, and a line is offered only if, after the
longest text it can hold, the output can still be completed within the
remaining token budget (a token is at least one ASCII character, so
characters bound tokens). Generation therefore always ends by completing the
output, never by running out of tokens mid-statement, for any model and any
sampling settings. The stages' constraints are in :mod:`..constraints`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

from .grammar import Grammar, Node, alt

REFUSAL_PREFIX = "# INFEASIBLE: "  # every stage may refuse with this one line


@dataclass(frozen=True)
class Forced:
    """Text the constraint writes itself."""

    text: str


@dataclass(frozen=True)
class Rewrite:
    """The line the model just wrote is taken back, and ``text`` written in its place (empty: the model writes
    another line instead)."""

    text: str


@dataclass(frozen=True)
class Choose:
    """The model writes the next line; ``grammar`` admits exactly the allowed lines. ``follows`` says, for a
    kind of line, what may start the text after it in the same token (blank lines where it says nothing; see
    :mod:`.line_ends`)."""

    grammar: Grammar
    options: dict[str, Grammar]  # the kinds of line allowed, in order of precedence
    follows: dict[str, Node] = field(default_factory=dict)

    def kind_of(self, line: str) -> str:
        """Which kind of line the model wrote (the first whose grammar admits it)."""
        return next((name for name, g in self.options.items() if g.matches(line)), "")


class Constraint(ABC):
    """A stage's output as a sequence of forced text and grammar-chosen lines."""

    def __init__(self) -> None:
        self.text = ""
        self.refusal: str | None = None
        self.grammars: list[str] = []
        self.capped: list[str] = []  # what the budget kept from being offered (reported, never silent)
        self._offered: Choose | None = None

    @abstractmethod
    def next(self, remaining: int) -> Forced | Choose | Rewrite | None:
        """What comes next, given ``remaining`` tokens of budget; None when the output is complete. A
        :class:`Rewrite` comes only right after a line the model wrote."""

    def feed(self, piece: str) -> None:
        """Record what was written (forced text, or the model's line; "" means it ended the output)."""
        offered, self._offered = self._offered, None
        kind = "forced" if offered is None else offered.kind_of(piece)
        if offered is not None and not kind:
            raise ValueError(f"the line {piece!r} is not one the grammar offered")
        self.text += piece
        if kind == "refusal":
            self.refusal = piece[len(REFUSAL_PREFIX):].strip()
        self._advance(kind, piece)

    @abstractmethod
    def _advance(self, kind: str, piece: str) -> None:
        """Move the state machine on after a line of a given kind."""

    def world_counts(self) -> tuple[int, int]:
        """Calls the world check tried, and lines for which it found nothing that succeeds."""
        return 0, 0

    @abstractmethod
    def minimum_budget(self) -> int:
        """The fewest tokens that always suffice to complete an output from the start."""

    def _choose(self, rules: dict[str, Node], options: dict[str, Node],
                follows: dict[str, Node] | None = None) -> Choose:
        grammar = Grammar({**rules, "root": alt(*options.values())})
        text = grammar.to_gbnf()
        if not self.grammars or self.grammars[-1] != text:
            self.grammars.append(text)
        self._offered = Choose(grammar, {k: Grammar({**rules, "root": v}) for k, v in options.items()},
                               {k: v for k, v in (follows or {}).items() if k in options})
        return self._offered


def longest(node: Node, rules: dict[str, Node]) -> int:
    return Grammar({**rules, "root": node}).max_length()
