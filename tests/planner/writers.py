"""Adversarial writers for a stage's constraint: they stand where the model stands and pick
lines the way a model most likely to break a guarantee would.

Every writer pays one token per character, the most a line can cost (the grammars admit
printable ASCII only, and every token spells at least one character), so a writer that
stays within its budget here stays within it for every real tokenizer.
"""

from __future__ import annotations

import random

from smartllm_local.planner.decoding.grammar import Grammar
from smartllm_local.planner.decoding.line_ends import BLANKS, TRAILING_SPACES
from smartllm_local.planner.decoding.matcher import Matcher
from smartllm_local.planner.decoding.protocol import Choose
from smartllm_local.planner.decoding.writer import Line, TokenWriter, Written

WRITERS = ("longest", "shortest", "random")


def writer(kind: str, rng: random.Random, refusals: float = 0.05):
    """A writer: the longest line offered, the shortest, or a random kind of line (comment, action,
    end ...) and a random line of that kind. A refusal is offered at the start of every stage; a
    writer takes it with probability ``refusals`` (it ends the plan, and tests nothing after it)."""
    def write(choose: Choose, remaining: int) -> tuple[str, int]:
        names = sorted(choose.options)
        if len(names) > 1 and "refusal" in names and rng.random() > refusals:
            names.remove("refusal")
        if kind == "random":
            text = choose.options[rng.choice(names)].sample(rng)
        else:
            texts = [choose.options[n].sample(rng, kind) for n in names]
            text = (max if kind == "longest" else min)(texts, key=len)
        return text, len(text) + (text == "")

    return write


class TokenAdversary(TokenWriter):
    """A writer that writes as a model does, adversarially: the carry and a line of the kind ``kind`` picks,
    in tokens of one character each (the most a text can cost), with spaces before the newline and, in the
    newline's token, a start of what may follow it (blank lines, an indentation, a ``#``); now and then it ends
    the sequence in the middle of a line, or at its start."""

    def __init__(self, kind: str, rng: random.Random, ends: float = 0.02, refusals: float = 0.05):
        self.kind, self.rng, self.ends, self.refusals = kind, rng, ends, refusals
        self.lines = self.ended = self.spilled = 0

    def write(self, line: Line, remaining: int) -> Written:
        self.lines += 1
        text = self._answer(line)
        head = text.index("\n", len(line.carry)) + 1 if line.carry.count("\n") < text.count("\n") else len(text)
        if self.rng.random() < self.ends:  # the end of sequence, anywhere before the line's newline
            self.ended += 1
            cut = self.rng.randint(0, head - 1)
            return Written(text[:cut], cut + 1, ended=True)
        self.spilled += head < len(text)
        return Written(text, head)  # what follows the newline is in the newline's token

    def _answer(self, line: Line) -> str:
        """The carry, then a line of the chosen kind (after what was written ahead), with an opened end when
        the grammar admits one."""
        choose = line.choose
        names = [n for n in sorted(choose.options) if _begins(choose.options[n], line.ahead)]
        if len(names) > 1 and "refusal" in names and self.rng.random() > self.refusals:
            names.remove("refusal")
        if self.kind == "random":
            name = self.rng.choice(names)
            own = _rest(choose.options[name], line.ahead, self.rng, "")
        else:
            texts = [(_rest(choose.options[n], line.ahead, self.rng, self.kind), n) for n in names]
            own, name = (max if self.kind == "longest" else min)(texts, key=lambda t: len(t[0]))
        plain = line.carry + own
        follows = choose.follows.get(name, BLANKS)
        spaces = " " * self.rng.randint(0, TRAILING_SPACES)
        spill = Grammar({"root": follows}).sample(self.rng)[: self.rng.randint(0, 4)]
        opened = plain[:-1] + spaces + "\n" + spill if plain.endswith("\n") else plain
        return opened if Matcher(line.grammar).advance(opened) else plain

    def force(self, text: str) -> int:
        return len(text)


def _begins(grammar: Grammar, text: str) -> bool:
    """Whether a line of ``grammar`` can begin with ``text`` (spaces begin a blank line too)."""
    return Matcher(grammar).advance(text) or (not text.strip(" ") and grammar.matches("\n"))


def _rest(grammar: Grammar, ahead: str, rng: random.Random, extreme: str) -> str:
    if not Matcher(grammar).advance(ahead):
        return "\n"  # the spaces written ahead were a blank line's
    return grammar.after(ahead).sample(rng, extreme)
