"""A llama-server slot kept as the in-process backend keeps its cache, so that greedy plans agree token for token.

llama.cpp computes a token evaluated alone slightly otherwise than one evaluated in a batch of two or more
(another kernel; how a batch is split otherwise changes nothing), and a small model's greedy choices
between near ties follow. In-process, a context's new part is one batch, text the grammar forces is one
batch, and each token the model chooses is evaluated alone. A server evaluates a request's new part as
one batch (the last token alone, again, if it holds all of it) and each token it writes alone; it keeps
what it wrote, also where the planner kept less of it and forced the rest. So before each request for a
line, the slot is brought to the in-process state: from the first token it holds otherwise, it is told to
drop the rest (a request for one other token there) and to evaluate the in-process batches one request
each, the last with the request itself.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from ..base import keep_whole, shared_prefix


class SlotMirror:
    """What one slot holds and what the in-process backend would hold: tokens, and which were evaluated alone."""

    def __init__(self, evaluate: Callable[[list[int]], None]):
        self.evaluate = evaluate  # sends a request that evaluates a prompt and writes nothing
        self.held: list[int] = []
        self.held_alone: list[bool] = []
        self.ours: list[int] = []
        self.ours_alone: list[bool] = []

    # ------------------------------------------------------ the in-process side

    def prefill(self, context: Sequence[int], prefixes: Sequence[int]) -> None:
        """The shared prefixes come from kept states (evaluated in batches), the rest is a batch of its own;
        without prefixes, the cache is kept and what the context adds is the batch."""
        last = max([0, *(end for end in prefixes if end < len(context))])
        if not last:
            self.sync(context)
            return
        self.ours = list(context)
        self.ours_alone = [False] * last + [len(context) - last == 1] * (len(context) - last)

    def sync(self, context: Sequence[int]) -> None:
        """What the context adds is one batch; a context the cache holds all of has its last token evaluated
        again (alone) unless it is what was just evaluated."""
        if list(context) == self.ours:
            return
        common = keep_whole(self.ours_alone, min(shared_prefix(self.ours, context), len(context) - 1))
        self.ours = self.ours[:common] + list(context[common:])
        self.ours_alone = self.ours_alone[:common] + [len(context) - common == 1] * (len(context) - common)

    def take(self, tokens: Sequence[int]) -> None:
        """Forced text, a way out of a loop or a chosen token: one batch."""
        self.ours += tokens
        self.ours_alone += [len(tokens) == 1] * len(tokens)

    # ------------------------------------------------------ the server's side

    def served(self, prompt: Sequence[int], evaluated_written: Sequence[int] = (),
               evaluated: int | None = None) -> None:
        """A request's prompt was evaluated from the first token the slot did not hold (its last token if it
        held all; ``evaluated``, where the server says how many it evaluated), then each written token that
        the server went on from, alone."""
        common = min(shared_prefix(self.held, prompt), len(prompt) - 1)
        if evaluated is not None and 0 < evaluated <= len(prompt):
            common = min(common, len(prompt) - evaluated)  # it held less than this worker knew (a restart)
        self.held = list(prompt) + list(evaluated_written)
        self.held_alone = (self.held_alone[:common] + [len(prompt) - common == 1] * (len(prompt) - common)
                           + [True] * len(evaluated_written))

    def prepare(self, prompt: Sequence[int]) -> None:
        """Bring the slot to the in-process state of ``prompt`` (which the in-process backend holds), all but
        the last batch, which the next request evaluates."""
        prompt = list(prompt)
        self.sync(prompt)  # nothing to do: the mirror follows every token the planner adds
        n, alone = len(prompt), self.ours_alone
        held = shared_prefix(self.held, prompt)
        same = next((p for p in range(held) if self.held_alone[p] != alone[p]), held)
        start = min(same, n - 1)  # a request re-evaluates at least its last token
        # Where that splits a batch, evaluate at least two of its tokens together.
        if start > 0 and not alone[start] and (start + 1 == n or alone[start + 1]):
            start -= 1
        if held > start:
            other = 1 if prompt[start] != 1 else 2  # any token but the one held there
            self.evaluate(prompt[:start] + [other])
        ends = [p for p in range(start + 1, n) if alone[p] or alone[p - 1]]  # batch boundaries after start
        for end in ends:
            self.evaluate(prompt[:end])
