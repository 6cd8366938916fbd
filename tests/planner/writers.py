"""Adversarial writers for a stage's constraint: they stand where the model stands and pick
lines the way a model most likely to break a guarantee would.

Every writer pays one token per character, the most a line can cost (the grammars admit
printable ASCII only, and every token spells at least one character), so a writer that
stays within its budget here stays within it for every real tokenizer.
"""

from __future__ import annotations

import random
import re

from smartllm_local.planner.decoding.grammar import Grammar
from smartllm_local.planner.decoding.line_ends import BLANKS, TRAILING_SPACES
from smartllm_local.planner.decoding.matcher import Matcher
from smartllm_local.planner.decoding.protocol import Choose
from smartllm_local.planner.decoding.writer import Line, TokenWriter, Written

WRITERS = ("longest", "shortest", "random")
_ROBOT = re.compile(r"robots\[(\d+)\]")


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


class Cycler(TokenWriter):
    """A writer that loops as a small model does: where the grammar admits the line ``k`` lines back (for the
    first ``k`` of ``sizes`` that it admits), it writes that line again, so a block of lines once written is
    written over and over; elsewhere a random line (never a refusal). It keeps the text it was given and
    wrote, as a model's context, and gives back what the driver takes back."""

    def __init__(self, rng: random.Random, sizes: tuple[int, ...] = (4, 2, 3, 5, 6, 8)):
        self.rng, self.sizes = rng, sizes
        self.text = ""
        self.taken_back = 0

    def write(self, line: Line, remaining: int) -> Written:
        lines = (self.text + line.carry).split("\n")[:-1]
        again = [lines[-k] + "\n" for k in self.sizes if k <= len(lines)]
        own = next((t for t in again if line.choose.grammar.matches(t)), None)
        if own is None:
            names = [n for n in sorted(line.choose.options) if n != "refusal"] or ["refusal"]
            own = line.choose.options[self.rng.choice(names)].sample(self.rng)
        text = line.carry + own
        self.text += text
        return Written(text, len(text))

    def force(self, text: str) -> int:
        self.text += text
        return len(text)

    def take_back(self, written: Written) -> None:
        assert self.text.endswith(written.text)
        self.text = self.text[: len(self.text) - len(written.text)]
        self.taken_back += 1


class Booker(TokenWriter):
    """An allocation writer that books busy robots: while it may add a thread to the block being written, it
    does, and gives it a robot list that names a robot some thread of the block already has, if the grammar
    offers one (of ``samples`` lines drawn); elsewhere a random line. Plain lines, one token a character."""

    def __init__(self, rng: random.Random, samples: int = 60):
        self.rng, self.samples = rng, samples
        self.text = ""
        self.booked = 0  # threads it gave a robot some thread of their block has

    def write(self, line: Line, remaining: int) -> Written:
        options = line.choose.options
        if "thread" in options:
            drawn = [options["thread"].sample(self.rng) for _ in range(self.samples)]
            busy = self._block_robots(self.text + line.carry)
            shared = [t for t in drawn if busy & set(_ROBOT.findall(t))]
            self.booked += bool(shared)
            own = (shared or drawn)[0]
        else:
            names = [n for n in sorted(options) if n != "refusal"] or ["refusal"]
            own = options[self.rng.choice(names)].sample(self.rng)
        self.text += line.carry + own
        return Written(line.carry + own, len(line.carry + own))

    def force(self, text: str) -> int:
        self.text += text
        return len(text)

    @staticmethod
    def _block_robots(text: str) -> set[str]:
        """The robots of the threads written since the last block was started."""
        block = text[text.rfind(".join()\n") + 1:]
        return {r for t in re.findall(r"^t\d+ = threading\.Thread\(.*$", block, re.M) for r in _ROBOT.findall(t)}
