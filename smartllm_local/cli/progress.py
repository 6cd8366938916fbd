"""A benchmark run's progress on stderr: a rich progress bar (ETA, the task and stage at hand, the
SR so far) on a terminal; one plain line per step when stderr is a file or a pipe (a log, CI)."""

from __future__ import annotations

import sys
from typing import IO, Any

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from ..benchmark.run import Progress as Step


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
