"""Driving a stage's constraint: forced text goes straight into the context, each
offered grammar goes to a writer (the model, or a sampler in tests), until the
constraint says the output is complete.
"""

from __future__ import annotations

import random
from collections.abc import Callable

from ..errors import SmartLLMError
from .constraints import Choose, Constraint, Forced

#: Writes one line for an offered grammar; returns the text and the tokens it cost.
Writer = Callable[[Choose, int], tuple[str, int]]
#: Puts forced text into the context; returns the tokens it cost.
Forcer = Callable[[str], int]


class BudgetError(Exception):
    """The output budget cannot hold even the shortest complete output."""


class GuaranteeError(SmartLLMError):
    """A stage's output broke a guarantee its constraint gives (a bug in the planner)."""


def run_constraint(constraint: Constraint, write: Writer, force: Forcer, budget: int) -> str:
    """Produce a stage's output within ``budget`` tokens."""
    if constraint.minimum_budget() > budget:
        raise BudgetError(
            f"{budget} output tokens cannot hold the shortest complete output "
            f"({constraint.minimum_budget()} characters); raise the output budget or --n-ctx"
        )
    used = 0
    while True:
        step = constraint.next(budget - used)
        if step is None:
            return constraint.text
        if isinstance(step, Forced):
            used += force(step.text)
            constraint.feed(step.text)
        else:
            text, cost = write(step, budget - used)
            used += cost
            constraint.feed(text)
        if used > budget:  # the constraint's bookkeeping failed: a bug, reported, never a plan
            raise GuaranteeError(f"the output used {used} tokens of a budget of {budget}: {constraint.text!r}")


def sample_output(constraint: Constraint, rng: random.Random, budget: int = 10_000) -> str:
    """A random output of a stage's grammar (every line sampled from the grammar offered)."""
    def write(choose: Choose, remaining: int) -> tuple[str, int]:
        text = choose.grammar.sample(rng)
        return text, len(text) + (1 if text == "" else 0)

    return run_constraint(constraint, write, len, budget)


def accepts(constraint: Constraint, text: str, budget: int = 100_000) -> bool:
    """Whether ``text`` is an output of the stage's grammar."""
    rest = text

    def write(choose: Choose, remaining: int) -> tuple[str, int]:
        nonlocal rest
        if rest == "":
            line = ""
        else:
            cut = rest.find("\n")
            line = rest if cut < 0 else rest[: cut + 1]
        if not choose.grammar.matches(line):
            raise _Rejected
        rest = rest[len(line):]
        return line, len(line) + 1

    def force(forced: str) -> int:
        nonlocal rest
        if not rest.startswith(forced):
            raise _Rejected
        rest = rest[len(forced):]
        return len(forced)

    try:
        run_constraint(constraint, write, force, budget)
    except (_Rejected, BudgetError):
        return False
    return rest == ""


class _Rejected(Exception):
    pass
