"""Several candidates of a stage for one task: candidate 0 as the planner's sampling says (greedy by default),
the others sampled at a temperature of their own, each from a seed of its own; one prompt for all.

Where the backend writes several sequences at once (:func:`~.backends.lanes.open_lanes`: llama.cpp decodes
them in one batch), each candidate is written in a thread of its own on a lane of it; elsewhere one after the
other, the prompt's state kept in the backend's cache between them. Each candidate's constraint is its own.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace

from .backends.base import Backend
from .backends.lanes import open_lanes
from .decoding.sampling import Sampling
from .verifier import SELECTORS, WEIGHTS, Weights

#: The temperature of candidates 1 and on (measured on the development half: docs/measurements.md).
CANDIDATE_TEMPERATURE = 0.7


@dataclass(frozen=True)
class Candidates:
    """How many candidates a stage writes, at what temperature the sampled ones, and how one is chosen
    (``verifier``: dry-run and checked against the stated goals; ``likelihood``: the model's mean
    log-probability alone)."""

    count: int = 1
    temperature: float = CANDIDATE_TEMPERATURE
    select: str = "verifier"
    weights: Weights = WEIGHTS

    def __post_init__(self) -> None:
        if self.count < 1:
            raise ValueError(f"candidates must be 1 or more, not {self.count}")
        if self.select not in SELECTORS:
            raise ValueError(f"select must be one of {', '.join(SELECTORS)}, not {self.select!r}")

    def sampling(self, base: Sampling, k: int) -> Sampling:
        """Candidate ``k``'s sampling: the planner's own for the first, the candidates' temperature and a seed
        of their own for the others."""
        return base if k == 0 else replace(base, temperature=self.temperature, seed=base.seed + k)


def write_all(backend: Backend, count: int, write: Callable[[Backend, int], object]) -> list[object]:
    """``write(backend_or_lane, k)`` for each candidate k, on lanes written together where the backend has them."""
    with open_lanes(backend, count) as (lanes, together):
        if not together:
            return [write(lane, k) for k, lane in enumerate(lanes)]
        with ThreadPoolExecutor(max_workers=count, thread_name_prefix="candidate") as pool:
            return list(pool.map(write, lanes, range(count)))


def mean_logprob(logprob: float, choices: int) -> float:
    """The mean log-probability of a candidate's chosen tokens (0 where the backend measures none)."""
    return logprob / choices if choices else 0.0

