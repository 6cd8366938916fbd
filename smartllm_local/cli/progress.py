"""Progress on stderr, so that stdout keeps only the results: a benchmark run's (a rich progress bar with ETA,
the task and stage at hand and the SR so far) and a plan's (each stage with its tokens, their rate and its time).
On a terminal it is live; where stderr is a file or a pipe (a log, CI), one plain line per step."""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Iterator
from typing import IO, Any

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    SpinnerColumn,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Column

from ..benchmark.run import Progress as Step
from ..planner.result import StageRecord


class RunProgress:
    """Use as a context manager around a run, and as the run's ``progress`` callback."""

    def __init__(self, label: str = "", stream: IO[str] | None = None):
        self.stream = stream or sys.stderr
        self.label = label
        self.bar: Progress | None = None
        self.task: Any = None

    def __enter__(self) -> RunProgress:
        if self.stream.isatty():
            self.bar = Progress(
                TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
                TimeElapsedColumn(), TextColumn("eta"), TimeRemainingColumn(), TextColumn("{task.fields[sr]}"),
                console=Console(file=self.stream), transient=False)
            self.bar.start()
            self.task = self.bar.add_task(self.label or "planning", total=None, sr="")
        return self

    def __call__(self, step: Step) -> None:
        sr = step.running_sr
        if self.bar is None:
            print(f"{self.label}: {step.line()}" if self.label else step.line(), file=self.stream, flush=True)
            return
        where = f"{step.phase} {step.task}".strip()
        self.bar.update(self.task, completed=step.done, total=step.total,
                        description=f"{self.label} {where}".strip(),
                        sr="" if sr is None else f"SR {sr:.2f} over {step.feasible_scored} feasible")

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.stop()


class PlanProgress:
    """A plan's stages as the planner tells them (a :class:`~smartllm_local.planner.progress.StageProgress`).

    On a terminal each stage has a live line: the prompt being evaluated, then the tokens written, their rate and
    the time, left as a summary when the stage ends. Elsewhere each stage gets one plain line as it ends. The
    first stage whose examples were evaluated rather than reused says why its prompt was slow, once: ``kept``
    says where the examples' states are kept for later (None: the backend does not say what it reuses, and
    nothing is explained). ``quiet`` shows nothing. Use as a context manager around the planning."""

    def __init__(self, console: Console | None = None, *, kept: str | None = None, quiet: bool = False):
        self.console = console or Console(stderr=True)
        self.kept, self.quiet = kept, quiet
        self.bar: Progress | None = None
        self._task: TaskID | None = None
        self._writing_since = 0.0
        self._explained = False
        self._note = ""  # the explanation, for the plain line of the stage it belongs to

    def __enter__(self) -> PlanProgress:
        if self.console.is_terminal and not self.quiet:
            # On a narrow terminal the detail wraps: the stage and its time stay whole.
            fixed = Column(no_wrap=True)
            self.bar = Progress(SpinnerColumn(finished_text="[green]✓", table_column=fixed),
                                TextColumn("[bold]{task.description:<13}", table_column=fixed),
                                TimeElapsedColumn(table_column=fixed),
                                TextColumn("{task.fields[detail]}", table_column=Column(overflow="fold")),
                                console=self.console)
            self.bar.start()
        return self

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.stop()
            self.bar = None

    @contextlib.contextmanager
    def loading(self, what: str) -> Iterator[None]:
        """A live line while ``what`` (the model) loads, on a terminal; gone once it has."""
        task = self.bar.add_task("loading", detail=what) if self.bar is not None else None
        try:
            yield
        finally:
            if task is not None and self.bar is not None:
                self.bar.remove_task(task)

    def stage_started(self, stage: str, prompt_tokens: int) -> None:
        if self.bar is not None:
            self._task = self.bar.add_task(stage, detail=f"evaluating the prompt ({prompt_tokens:,} tokens)"
                                           if prompt_tokens else "planning without the model")

    def prompt_evaluated(self, stage: str, *, tokens: int, shared: int, reused: int, seconds: float) -> None:
        self._writing_since = time.perf_counter()
        evaluated = max(0, shared - reused)
        if evaluated and self.kept and not self._explained:
            self._explained = True
            self._note = f"its {evaluated:,} tokens of examples were evaluated, as they are the first time: {self.kept}"
            if self.bar is not None:
                self.bar.console.print(f"{stage}: the prompt took {seconds:.1f} s: {self._note}", highlight=False)
                self._note = ""
        if self.bar is not None and self._task is not None:
            self.bar.update(self._task, detail=f"prompt evaluated in {seconds:.1f} s; writing")

    def tokens_written(self, stage: str, generated: int, forced: int) -> None:
        if self.bar is None or self._task is None:
            return
        seconds = time.perf_counter() - self._writing_since
        self.bar.update(self._task, detail=f"{_written(generated, forced)}, {_rate(generated + forced, seconds)}")

    def stage_ended(self, record: StageRecord) -> None:
        summary = stage_summary(record)
        if self.bar is not None and self._task is not None:
            self.bar.update(self._task, detail=summary, total=1, completed=1)
            self.bar.stop_task(self._task)
            self._task = None
        elif self.bar is None and not self.quiet:
            note, self._note = (f" ({self._note})" if self._note else ""), ""
            print(f"{record.stage}: {summary}{note}", file=self.console.file, flush=True)


def stage_summary(record: StageRecord) -> str:
    """A finished stage in a line: its prompt, the tokens it wrote (the model's and those the grammar forced) and
    how fast, and its time; for a stage no model wrote (a search), the first line it wrote, and its time."""
    if not (record.prompt_tokens or record.generated_tokens or record.forced_tokens):  # no model wrote it
        said = record.error or next((line.lstrip("# ") for line in record.output.splitlines() if line.strip()), "")
        return f"{said}; {record.seconds:.1f} s in all"
    if not record.prompted and not record.generated_tokens:  # every line was one way to write: no model asked
        return (f"nothing for the model to choose: {record.forced_tokens:,} tokens written by the planner, the prompt "
                f"({record.prompt_tokens:,} tokens) not evaluated; {record.seconds:.1f} s in all")
    writing = max(0.0, record.seconds - record.prompt_seconds)
    return (f"prompt {record.prompt_tokens:,} tokens ({record.reused_tokens:,} reused) in "
            f"{record.prompt_seconds:.1f} s; {_written(record.generated_tokens, record.forced_tokens)} in "
            f"{writing:.1f} s, {_rate(record.generated_tokens + record.forced_tokens, writing)}; "
            f"{record.seconds:.1f} s in all")


def _written(generated: int, forced: int) -> str:
    return f"{generated + forced:,} tokens written ({generated:,} by the model)"


def _rate(tokens: int, seconds: float) -> str:
    return f"{tokens / seconds if seconds > 0 else 0.0:.1f} tokens/s"
