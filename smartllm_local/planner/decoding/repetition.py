"""A guard against degenerate repetition: free text that starts saying one thing over and over ends there.

Small models fall into loops inside free text ("1.1.1.1.", "the glass of the glass of the
glass of the", "PickupObject, PickupObject, ..."), and a grammar that bounds a comment's
length still lets a loop run to that bound (SmolLM2's coalitions over the household benchmark:
half of what it decoded). Banning the looping token does not help (the model
wanders into the next loop), so when a candidate token would close a loop, the backend
ends the free text instead, writing the grammar's shortest way out of it
(:meth:`Matcher.shortest_way`: `` (`` before a summary's skills, ``;`` before a coalition's
team, the newline after a comment) and letting the model go on from there. Only where no
grammar gives a way out is the best token that closes no loop taken instead. Either way the
guard only ever chooses among what the grammar admits.

Unlike a repetition penalty (llama.cpp's ``repeat_penalty``, its DRY sampler), it looks at
the current line alone and acts only on a third copy in a row, so the code a plan repeats
from line to line (``GoToObject('Bread')`` in every function) and the robots a coalition
names twice in a line are never touched.

Whole lines loop too: Qwen2.5-Coder-1.5B wrote go to, open, go to, close the cabinet three
times over in two sub-tasks, each line different from the one before it. So the same rule holds
for a block of lines (:meth:`LoopGuard.cycles`): a line may not begin a third copy in a row
of a block of up to ``block`` lines. That rule is applied where a stage's output is written
line by line, whatever the backend (:mod:`..decoding.writer`), which takes such a line back and
writes the constraint's shortest way out of the block instead.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LoopGuard:
    """A line may not end with a stretch of ``unit`` characters or fewer repeated ``times`` times in a
    row, or as many more times as it takes the repeats to span ``span`` characters (so "ll", "..."
    and "1.1.1" stay allowed, "1.1.1.1.1." does not); nor may a line begin the ``times``-th copy in a
    row of a block of ``block`` lines or fewer."""

    times: int = 3
    span: int = 9
    unit: int = 32
    block: int = 12  # lines: two copies of a block this long fill a function of 12 steps with their comments

    def loops(self, line: str) -> bool:
        """Whether ``line`` ends in a loop."""
        for size in range(1, min(self.unit, len(line) // self.times) + 1):
            repeats = max(self.times, -(-self.span // size))
            tail = line[-size * repeats:]
            if len(tail) == size * repeats and tail == tail[:size] * repeats:
                return True
        return False

    def cycles(self, lines: Sequence[str]) -> bool:
        """Whether the last of ``lines`` begins the ``times``-th copy in a row of a block of up to ``block``
        lines (three identical lines in a row are a block of one); a line that is not a comment, also counting
        the lines that are not comments only (the same steps under other comments are the same loop)."""
        if self._cycles(lines):
            return True
        return bool(lines) and not _comment(lines[-1]) and self._cycles([line for line in lines if not _comment(line)])

    def _cycles(self, lines: Sequence[str]) -> bool:
        for size in range(1, self.block + 1):
            n = (self.times - 1) * size + 1
            if n > len(lines):
                return False
            tail = lines[-n:]
            if all(tail[i] == tail[i + size] for i in range(n - size)):
                return True
        return False


def _comment(line: str) -> bool:
    return line.lstrip().startswith("#")


#: How many of the likeliest admitted tokens (or draws) are tried for one that closes no loop, by every
#: backend alike.
TRIES = 64


def current_line(text: str) -> str:
    """The text after the last newline: the line a guard looks at."""
    return text[text.rfind("\n") + 1:]


def draw(probs: np.ndarray, rng: np.random.Generator, avoid: Callable[[int], bool] | None = None,
         tries: int = TRIES) -> int:
    """A token drawn from ``probs`` (unnormalised; changed in place), drawn again without each draw ``avoid``
    refuses, which samples exactly the tokens it allows; the first draw if ``tries`` draws are all refused."""
    first = -1
    for _ in range(tries if avoid else 1):
        token = int(rng.choice(len(probs), p=probs / probs.sum()))
        first = token if first < 0 else first
        if avoid is None or not avoid(token):
            return token
        probs[token] = 0.0
        if probs.sum() <= 0:
            break
    return first
