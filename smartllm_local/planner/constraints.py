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
sampling settings. The plans' constraint is in :mod:`.plan_constraint`, the
coalition's in :mod:`.coalition`.

Output formats (the prompt examples under domains/household/prompts/ follow them):

- decomposition: summary lines ``# SubTask k: <what> (skills: A, B)``, an
  order line ``# <how they are ordered>``, a blank line, functions
  ``def subtask<k>_<name>():`` with indented skill calls and comments, then
  the orchestration (threads started and joined together, or direct calls);
- coalition: one line per sub-task, reasoning before the team, ``# SubTask k
  (<function>): needs <skills>, lifting <m> kg; <analysis>; so robots[i] and
  robots[j]``;
- allocation: the decomposition's functions again, each taking
  ``robot_list`` and naming robots in every call, then the orchestration
  with ``args=([robots[i], ...],)``.

A stage may instead answer with one line ``# INFEASIBLE: <reason>``.
"""

from __future__ import annotations

import string
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import combinations, permutations

from .grammar import Grammar, Node, alt, chars, opt, rep, seq

COMMENT_CHARS = frozenset(c for c in string.printable if c not in "\t\n\r\x0b\x0c")
SUMMARY_CHARS = COMMENT_CHARS - set("()")
ORDER_CHARS = COMMENT_CHARS - set(":")  # so the order line cannot pass for one more "# SubTask k: ..."
REASON_CHARS = frozenset(string.ascii_letters + " ,.;:'-")
NAME_FIRST = frozenset(string.ascii_lowercase)
NAME_REST = frozenset(string.ascii_lowercase + string.digits + "_")
COMMENT_LEN = 80  # an allocated plan's comments say why a robot does a step (the examples': up to 79)
STEP_COMMENT_LEN = 48  # a decomposition's say what a step is for (the examples': up to 47)
SUMMARY_LEN = 60
ORDER_LEN = 100
REASON_LEN = 100
NAME_LEN = 30
MAX_SUBTASKS = 8
MAX_STEPS = 12
INDENT = "    "
REFUSAL_PREFIX = "# INFEASIBLE: "


@dataclass(frozen=True)
class Forced:
    """Text the constraint writes itself."""

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


def ordered_subset(items: Sequence[str], separator: str) -> Node:
    """One or more of ``items``, each at most once, in the given order.

    Written as a choice of the first item followed by optional later ones, so
    the grammar (and its regex) grows with the square of the items, not 2^n.
    """
    return alt(*(seq(items[k], *(opt(seq(separator, item)) for item in items[k + 1:])) for k in range(len(items))))


def robot_list(team_size: int, need: int, separator: str, *, ordered: bool = False) -> Node:
    """A list of at least ``need`` distinct robots of the team, written robots[i].

    A set (``ordered=False``) is listed in increasing order; an ordered list
    (where position matters, as robot_list[i] does) may come in any order.
    Teams too big to enumerate (over 6 robots, 5 when ordered) get lists of
    any robots of the right length.
    """
    names = [f"robots[{i}]" for i in range(team_size)]
    if team_size <= (5 if ordered else 6):
        pick = permutations if ordered else combinations
        return alt(*(separator.join(c) for n in range(max(1, need), team_size + 1) for c in pick(names, n)))
    robot = alt(*names)
    return seq(robot, rep(seq(separator, robot), max(0, need - 1), team_size - 1))


def text_run(charset: frozenset[str], length: int) -> Node:
    """Free text of 1 to ``length`` characters, which does not start with a space: it follows forced text
    that ends in one, and a model writes its words with their leading space (`` put``), so that space is the
    model's own token and never doubled."""
    if " " not in charset:
        return rep(chars(charset), 1, length)
    return seq(chars(charset - {" "}), rep(chars(charset), 0, length - 1))


def comment_text(length: int) -> Node:
    """Free comment text that cannot read as a refusal: it starts neither with a space nor with
    the word INFEASIBLE, so no comment inside a plan matches the parser's ``# INFEASIBLE:`` line."""
    word = REFUSAL_PREFIX[2:].split(":")[0]
    options: list[Node] = [seq(chars(COMMENT_CHARS - {" ", word[0]}), rep(chars(COMMENT_CHARS), 0, length - 1))]
    for j in range(1, min(len(word), length + 1)):
        if j == length:
            options.append(word[:j])
            continue
        rest = seq(chars(COMMENT_CHARS - {word[j]}), rep(chars(COMMENT_CHARS), 0, length - j - 1))
        options.append(seq(word[:j], opt(rest)))
    return alt(*options)


def refusal_text_len() -> int:
    """The longest reason a refusal line may give."""
    return COMMENT_LEN


def refusal_line(length: int = COMMENT_LEN) -> Node:
    return seq(REFUSAL_PREFIX, text_run(COMMENT_CHARS, length), "\n")


class Constraint(ABC):
    """A stage's output as a sequence of forced text and grammar-chosen lines."""

    def __init__(self) -> None:
        self.text = ""
        self.refusal: str | None = None
        self.grammars: list[str] = []
        self.capped: list[str] = []  # what the budget kept from being offered (reported, never silent)
        self._offered: Choose | None = None

    @abstractmethod
    def next(self, remaining: int) -> Forced | Choose | None:
        """What comes next, given ``remaining`` tokens of budget; None when the output is complete."""

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
