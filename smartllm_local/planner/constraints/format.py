"""The text of the plans the stages write: character sets, lengths and the pieces of grammar
every stage builds lines from.

Output formats (the worked examples in each domain's prompts follow them):

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
from collections.abc import Sequence
from itertools import combinations, permutations

from ..decoding.grammar import Node, alt, chars, opt, rep, seq
from ..decoding.protocol import REFUSAL_PREFIX

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


def ordered_subset(items: Sequence[str], separator: str) -> Node:
    """One or more of ``items``, each at most once, in the given order.

    Written as a choice of the first item followed by optional later ones, so
    the grammar (and its regex) grows with the square of the items, not 2^n.
    """
    return alt(*(seq(items[k], *(opt(seq(separator, item)) for item in items[k + 1:])) for k in range(len(items))))


def robot_list(team_size: int, need: int, separator: str, *, ordered: bool = False,
               among: Sequence[int] | None = None) -> Node:
    """A list of at least ``need`` distinct robots of the team (of those ``among`` it, if given), written robots[i].

    A set (``ordered=False``) is listed in increasing order; an ordered list
    (where position matters, as robot_list[i] does) may come in any order.
    Teams too big to enumerate (over 6 robots, 5 when ordered) get lists of
    any robots of the right length.
    """
    names = [f"robots[{i}]" for i in (range(team_size) if among is None else among)]
    if len(names) <= (5 if ordered else 6):
        pick = permutations if ordered else combinations
        return alt(*(separator.join(c) for n in range(max(1, need), len(names) + 1) for c in pick(names, n)))
    robot = alt(*names)
    return seq(robot, rep(seq(separator, robot), max(0, need - 1), len(names) - 1))


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
