"""What planning a task leaves: each stage's record, and the task's result, its records by stage name.

Below the stages that write them, the planner that runs them and the classical planner that writes an
allocation stage's record too, so that each of those can hand one on without importing the others.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from ..plan_language import Plan
from .decoding.sampling import Generated

_TRANSIENT = frozenset({"plan", "context"})


@dataclass
class StageRecord:
    """Everything about one stage's run, as written to --out."""

    stage: str
    prompt: str = ""
    grammars: list[str] = field(default_factory=list)
    raw: str = ""
    output: str = ""
    refusal: str | None = None
    refused_by: str = ""  # who refused: "model", or "grammar" when it admitted nothing else, or "rule"
    prompt_tokens: int = 0
    shared_tokens: int = 0  # of the prompt's tokens, those of the examples every task shares
    reused_tokens: int = 0  # of those, the ones the backend had kept (from an earlier task or process)
    generated_tokens: int = 0
    forced_tokens: int = 0
    seconds: float = 0.0
    prompt_seconds: float = 0.0  # of those, evaluating the prompt (the time to the first token)
    prompted: bool = False  # whether the prompt was evaluated: not where the model had nothing to choose
    output_budget: int = 0
    examples: list[str] = field(default_factory=list)
    dropped: list[str] = field(default_factory=list)
    capped: list[str] = field(default_factory=list)  # what the output budget kept the grammar from offering
    world_tries: int = 0  # calls the world check tried
    dead_ends: int = 0  # lines for which it found nothing that succeeds
    ended_at_goals: bool = False  # a decomposition's next sub-task was withheld: the stated goals all held
    repairs: list[dict[str, Any]] = field(default_factory=list)  # the planner's lines before a model's (repair)
    unrepaired: int = 0  # lines the model wrote that the planner could not enable (taken back)
    finish: dict[str, Any] | None = None  # the planner's last sub-task: goals met, lines, search, `into` (finish_fold)
    errands: list[str] = field(default_factory=list)  # lines taken out as errands (errands.py, in_turn.py)
    idle_steps: list[str] = field(default_factory=list)  # a decomposition's lines taken out as idle (idle_steps.py)
    joined: list[str] = field(default_factory=list)  # sub-tasks written into one before them ("b into a"; joined.py)
    moved: list[str] = field(default_factory=list)  # openings moved into the sub-task they serve (opening_moved.py)
    put_away: list[str] = field(default_factory=list)  # lines putting a thing kept in hand where a goal wants it
    executable: list[str] = field(default_factory=list)  # an allocation's changes for its run to fail no call
    dropped_goals: list[str] = field(default_factory=list)  # stated goals out of reach nobody asked for (asked.py)
    placed_already: list[str] = field(default_factory=list)  # stated things where the scene began with them (goal)
    unasked: list[str] = field(default_factory=list)  # stated goals nobody asked for, left out (goal)
    overturned: str = ""  # a goal stage's refusal for a thing the scene has, stated again without it (asked.py)
    placements: list[str] = field(default_factory=list)  # the goal-planner's holders read from the steps (readings.py)
    loops_ended: int = 0  # loops the loop guard ended: in free text, and of whole lines (see decoding.repetition)
    choices: int = 0  # tokens the model chose (not forced), where the backend measures them
    refused: int = 0  # of those, where the model's likeliest token was one the grammar refused
    logprob: float = 0.0  # their log-probabilities under the unconstrained model, summed
    completed_lines: int = 0  # lines the planner completed after the model ended the sequence
    spilled: int = 0  # line ends where the model's token ran on into the next line
    error: str = ""
    plan: object = None  # the parsed plan of a plan stage
    context: list[int] = field(default_factory=list)  # the tokens the stage ended with, for the next to go on from
    chat_template: str = ""  # "applied", "none (base model)" or "off" (--chat-template none)
    candidates: list[dict[str, Any]] = field(default_factory=list)  # each candidate written, its check and score

    def saved(self) -> dict[str, Any]:
        """Everything but the parsed plan (parsed again when a run resumes) and the tokens (not kept)."""
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name not in _TRANSIENT}

    @classmethod
    def restored(cls, data: Mapping[str, Any]) -> StageRecord:
        """A saved record; one saved before a field was added gets its default."""
        known = {f.name for f in fields(cls)} - _TRANSIENT
        if not isinstance(data, Mapping) or not set(data) <= known or "stage" not in data:
            raise ValueError("not a saved stage record")
        return cls(**data)

    def note(self, result: Generated) -> None:
        """Count how far the grammar bent the model in a backend's answer."""
        self.choices += result.choices
        self.refused += result.refused
        self.logprob += result.logprob

    def bending(self) -> dict[str, float | int | None]:
        """The share of the model's choices where its likeliest token was refused, and the mean log-probability
        of what it chose, under the unconstrained model (None where the backend does not measure them)."""
        if not self.choices:
            return {"choices": 0, "refused_share": None, "mean_logprob": None}
        return {"choices": self.choices, "refused_share": round(self.refused / self.choices, 4),
                "mean_logprob": round(self.logprob / self.choices, 4)}

    @property
    def tokens_per_second(self) -> float:
        return self.generated_tokens / self.seconds if self.seconds else 0.0

    def timings(self) -> dict[str, float | int | str | list[str]]:
        return {
            "chat_template": self.chat_template,
            "prompt_tokens": self.prompt_tokens, "shared_tokens": self.shared_tokens,
            "prompted": self.prompted, "reused_tokens": self.reused_tokens, "generated_tokens": self.generated_tokens,
            "forced_tokens": self.forced_tokens, "output_budget": self.output_budget,
            "seconds": round(self.seconds, 3), "prompt_seconds": round(self.prompt_seconds, 3),
            "tokens_per_second": round(self.tokens_per_second, 2),
            "examples": self.examples, "dropped_examples": self.dropped, "capped_by_budget": self.capped,
            "world_check": {"tries": self.world_tries, "dead_ends": self.dead_ends},
            "loops_ended": self.loops_ended,
            "bending": self.bending(),
            "completed_lines": self.completed_lines, "spilled_line_ends": self.spilled,
        }


@dataclass
class PlanResult:
    """A task's way through the stages: each stage's record under its name, in the order they ran."""

    instruction: str
    floor_plan: str
    robots: list[int]
    stages: dict[str, StageRecord] = field(default_factory=dict)
    allocated: str = ""
    plan: Plan | None = None
    refusal: str | None = None
    error: str = ""

    def stage(self, name: str) -> StageRecord:
        """The record of the stage ``name`` (a KeyError where it has not run)."""
        if name not in self.stages:
            raise KeyError(f"the stage {name!r} has not run for this task")
        return self.stages[name]

    def add(self, record: StageRecord) -> None:
        """Keep a stage's record under its name (a stage runs once for a task: a second record is a bug)."""
        if record.stage in self.stages:
            raise ValueError(f"the stage {record.stage!r} has already run for this task")
        self.stages[record.stage] = record

    @property
    def goes_on(self) -> bool:
        """Whether a next stage may run: no stage so far refused the task or failed."""
        return self.refusal is None and not self.error

    @property
    def refused_by(self) -> str | None:
        """Who refused: "grammar" (no team can do a sub-task the model wrote: it admitted nothing else),
        "rule" (a rule-based allocation found no team), "planner" (the goal-planner's search found no plan),
        "goal check" (a stated goal the team cannot reach), "world check" (no call of the allocated plan succeeds
        with the team), "model", or None."""
        if self.refusal is None:
            return None
        return next((r.refused_by for r in self.stages.values() if r.refusal is not None and r.refused_by), "model")

    @property
    def notices(self) -> list[str]:
        dropped = [f"{r.stage}: dropped example(s) {', '.join(r.dropped)} to fit the context"
                   for r in self.stages.values() if r.dropped]
        capped = [f"{r.stage}: the output budget ({r.output_budget} tokens) left no room for {', '.join(r.capped)}"
                  for r in self.stages.values() if r.capped]
        return dropped + capped
