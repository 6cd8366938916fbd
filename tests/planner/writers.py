"""Adversarial writers for a stage's constraint: they stand where the model stands and pick
lines the way a model most likely to break a guarantee would.

Every writer pays one token per character, the most a line can cost (the grammars admit
printable ASCII only, and every token spells at least one character), so a writer that
stays within its budget here stays within it for every real tokenizer.
"""

from __future__ import annotations

import random

from smartllm_local.planner.constraints import Choose

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
