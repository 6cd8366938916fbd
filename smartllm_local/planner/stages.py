"""Running one stage: fit its prompt into the context, generate under its constraint, check the result.

Context budget: the prompt is measured with the loaded model's tokenizer;
when prompt + output budget exceed the context, examples are dropped from the
last, and the drop is recorded and reported rather than the prompt being
truncated or the run failing. Dropping from the last keeps the examples left a
prefix of every other task's, whose state the backend keeps (see
prefix_cache.py).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import GrammarMismatchError, PlanError, UserError
from .backends.base import Backend
from .decoding.matcher import Matcher
from .decoding.protocol import Constraint
from .decoding.sampling import Sampling
from .decoding.writer import BudgetError, GuaranteeError, Line, Report, TokenWriter, Written, run_tokens
from .progress import SILENT, StageProgress
from .prompting.chat import APPLIED, ChatFormat, answer_code, prompt_tokens
from .prompting.prompts import Example, Prompt
from .result import StageRecord

STOP_STRINGS = {
    "decomposition": ("\n# Example", "\n# Your task", "\n# Task Description", "\nobjects ="),
    "coalition": ("\n\n", "\n# Allocated plan", "\n# Example", "\n# Your plan", "\ndef "),
    "allocation": ("\n# Example", "\n# Your plan", "\n# Task Description"),
    "goal": ("\n\n", "\n# Example", "\n# Your task", "\n# Task Description"),
}


@dataclass(frozen=True)
class Fitted:
    """A prompt as the model gets it: its text, its tokens, where in them each shared prefix ends (the
    first is what every task's prompt begins with), and the examples it kept and dropped."""

    text: str
    tokens: list[int]
    prefixes: tuple[int, ...] = ()
    kept: list[Example] = field(default_factory=list)
    dropped: list[Example] = field(default_factory=list)
    continues: bool = False  # it goes on from the context the backend was left with: no prefix is loaded again


def fit_prompt(
    build: Callable[[Sequence[Example]], Prompt],
    examples: Sequence[Example],
    backend: Backend,
    output_budget: int,
    chat: ChatFormat | None = None,
) -> Fitted:
    """The prompt with as many examples as fit, dropping the last first.

    What must fit is the prompt as the model gets it (in its chat template, with ``chat``).
    """
    kept = list(examples)
    while True:
        text, tokens, prefixes = prompt_tokens(backend, build(kept), chat)
        if len(tokens) + output_budget < backend.n_ctx:
            return Fitted(text, tokens, prefixes, kept, list(examples[len(kept):]))
        if not kept:
            raise UserError(
                f"the prompt alone ({len(tokens)} tokens) and an output budget of {output_budget} tokens "
                f"exceed the model's context of {backend.n_ctx} tokens; raise --n-ctx"
            )
        kept.pop()


def run_stage(
    record: StageRecord,
    backend: Backend,
    prompt: Fitted,
    constraint: Constraint | None,
    *,
    output_budget: int,
    sampling: Sampling,
    rng: np.random.Generator,
    progress: StageProgress = SILENT,
) -> None:
    """Generate a stage's output into ``record`` (constrained, or free with stop strings), telling ``progress``
    as it goes."""
    context = list(prompt.tokens)
    record.prompt, record.prompt_tokens = prompt.text, len(context)
    record.shared_tokens = prompt.prefixes[0] if prompt.prefixes else 0
    record.examples, record.dropped = [e.name for e in prompt.kept], [e.name for e in prompt.dropped]
    record.output_budget = output_budget
    progress.stage_started(record.stage, len(context))
    started = time.perf_counter()

    def prefill() -> None:
        """Evaluate the prompt: when the model is first asked to write (a stage whose every line the constraint
        leaves one way to write never asks it, and costs no evaluation)."""
        if record.prompted:
            return
        began = time.perf_counter()
        record.reused_tokens = backend.prefill(prompt.tokens, () if prompt.continues else prompt.prefixes)
        record.prompt_seconds, record.prompted = time.perf_counter() - began, True
        progress.prompt_evaluated(record.stage, tokens=len(prompt.tokens), shared=record.shared_tokens,
                                  reused=record.reused_tokens, seconds=record.prompt_seconds)

    if constraint is None:
        prefill()
        _generate_freely(record, backend, context, output_budget=output_budget, sampling=sampling, rng=rng)
        record.seconds = time.perf_counter() - started
    else:
        _generate_constrained(record, backend, context, constraint, output_budget=output_budget,
                              sampling=sampling, rng=rng, progress=progress, started=started, prefill=prefill)
    progress.stage_ended(record)


def _generate_freely(record: StageRecord, backend: Backend, context: list[int], *, output_budget: int,
                     sampling: Sampling, rng: np.random.Generator) -> None:
    """The output without a grammar: the model writes until a stop string, the end of sequence or the budget."""
    stops = STOP_STRINGS[record.stage]
    chat = record.chat_template == APPLIED  # a chat answer's prose has paragraphs: its code is cut afterwards
    result = backend.generate(context, grammar=None, max_tokens=output_budget, sampling=sampling,
                              stop=[s for s in stops if s != "\n\n"] if chat else stops, rng=rng)
    record.generated_tokens = len(result.tokens)
    record.loops_ended = result.loops
    record.note(result)
    record.raw = result.text.rstrip() + "\n"
    record.output = answer_code(record.raw, stops) if chat else record.raw


def _generate_constrained(record: StageRecord, backend: Backend, context: list[int], constraint: Constraint, *,
                          output_budget: int, sampling: Sampling, rng: np.random.Generator,
                          progress: StageProgress, started: float, prefill: Callable[[], None]) -> None:
    """The output line by line under the stage's constraint, in ``context`` (which it extends); ``prefill``
    evaluates the prompt, before the model's first line."""
    writer = _StageWriter(record, backend, context, sampling, rng, progress, prefill)
    report = Report()
    record.context = context
    try:
        record.output = run_tokens(constraint, writer, output_budget, report, open_ends=sampling.aligned,
                                   guard=sampling.loop_guard)
    except BudgetError as exc:
        raise UserError(f"{record.stage}: {exc}") from exc
    except GuaranteeError as exc:
        raise GuaranteeError(f"{record.stage} stage: {exc}") from exc
    finally:
        record.seconds = time.perf_counter() - started
        record.raw = writer.raw
        record.grammars = list(dict.fromkeys(constraint.grammars))
        record.capped = list(constraint.capped)
        record.world_tries, record.dead_ends = constraint.world_counts()
        record.completed_lines, record.spilled = report.completed_lines, report.spilled
        record.loops_ended += report.cycles_ended
    record.refusal = constraint.refusal


class _StageWriter(TokenWriter):
    """The backend as a stage's writer: each line generated under its grammar, in the stage's context."""

    def __init__(self, record: StageRecord, backend: Backend, context: list[int], sampling: Sampling,
                 rng: np.random.Generator, progress: StageProgress, prefill: Callable[[], None]):
        self.record, self.backend, self.context, self.sampling, self.rng = record, backend, context, sampling, rng
        self.progress, self.prefill = progress, prefill
        self.raw = ""  # what was written, as it was written (the output is that, normalized)
        self._last = 0  # tokens of the last line written, and of text forced after it

    def write(self, line: Line, remaining: int) -> Written:
        record = self.record
        self.prefill()
        try:
            result = self.backend.generate(self.context, grammar=line.grammar, max_tokens=line.grammar.max_length() + 1,
                                           sampling=self.sampling, rng=self.rng, lines=line.lines)
        except GrammarMismatchError as exc:
            raise exc.in_stage(record.stage) from exc
        if not Matcher(line.grammar).advance(result.text):
            raise GrammarMismatchError(result.text, "the backend wrote it as a line, the stage's grammar does not "
                                       "allow it", record.stage)
        self.context.extend(result.tokens)
        self.raw += result.text
        self._last = len(result.tokens)
        ended = result.stop == "eos"
        record.generated_tokens += len(result.tokens) - result.forced + ended
        record.forced_tokens += result.forced
        record.loops_ended += result.loops
        record.note(result)
        self.progress.tokens_written(record.stage, record.generated_tokens, record.forced_tokens)
        return Written(result.text, len(result.tokens) + ended, ended=ended and result.text.count("\n") < line.lines)

    def take_back(self, written: Written) -> None:
        """The line just written (and what was forced after it) is not kept (it began a loop of lines, or the
        constraint writes another in its place): out of the context (the backend evaluates the context it is
        next given), and out of ``raw``, which stays the text the model was given."""
        del self.context[len(self.context) - self._last:]
        self.raw = self.raw[: len(self.raw) - len(written.text)]

    def force(self, text: str) -> int:
        tokens = self.backend.tokenize_continuation(text)  # one batch, whatever the tokenizer family
        self.context.extend(tokens)
        self._last += len(tokens)
        self.raw += text
        self.record.forced_tokens += len(tokens)
        self.progress.tokens_written(self.record.stage, self.record.generated_tokens, self.record.forced_tokens)
        return len(tokens)


#: Tokens a forced text may cost beyond its own spelling: text carried over from the line before is forced with it.
CARRIED = 4


def spelled_cost(backend: Backend) -> Callable[[str], int]:
    """What a text the planner writes itself costs on ``backend``, in tokens, as the stage's writer forces it: the
    1.5B's two long sub-tasks left 608 tokens, and the planner's last sub-task of 15 steps, 620 characters but 180
    tokens, was not written where a character was counted a token (dev6-s1)."""
    return lambda text: len(backend.tokenize_continuation(text)) + CARRIED


def check_output(record: StageRecord, validate: Callable[[str], object]) -> object | None:
    """Validate a stage's output; a failure is recorded (free generation can produce anything)."""
    if record.refusal is not None:
        return None
    try:
        return validate(record.output)
    except PlanError as exc:
        record.error = f"{record.stage} output is not a valid plan: {exc}"
        return None
