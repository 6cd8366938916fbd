"""What a planner tells of its stages while it runs them, for whoever shows it (the CLI's progress display).

A stage on a small machine takes minutes; the planner says as it goes where it is, so that a user can tell
planning from a hang. It only calls these methods and never renders anything itself (the planner does not
import the CLI). They are called once per line the stage writes or forces, never once per sampled token, and
the default, :data:`SILENT`, does nothing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from .result import StageRecord


class StageProgress(Protocol):
    """The events of one stage, in this order: started, prompt evaluated, tokens written (any number), ended."""

    def stage_started(self, stage: str, prompt_tokens: int) -> None:
        """``stage`` begins: its prompt of ``prompt_tokens`` tokens is about to be evaluated (0 for a stage no model
        writes, as the goal-planner's search; only its end follows)."""

    def prompt_evaluated(self, stage: str, *, tokens: int, shared: int, reused: int, seconds: float) -> None:
        """The prompt is evaluated, in ``seconds``: ``reused`` of its ``tokens`` came from states kept by an
        earlier task or process. Of its ``shared`` tokens (the examples, the same for every task) those not
        reused were evaluated now, and the backend keeps them for later (the slow first time)."""

    def tokens_written(self, stage: str, generated: int, forced: int) -> None:
        """The stage's output so far: ``generated`` tokens the model chose, ``forced`` the grammar wrote."""

    def stage_ended(self, record: StageRecord) -> None:
        """``record``'s stage is done: its tokens and times are final."""


class Silent:
    """Tells nobody: the planner's default."""

    def stage_started(self, stage: str, prompt_tokens: int) -> None:
        pass

    def prompt_evaluated(self, stage: str, *, tokens: int, shared: int, reused: int, seconds: float) -> None:
        pass

    def tokens_written(self, stage: str, generated: int, forced: int) -> None:
        pass

    def stage_ended(self, record: StageRecord) -> None:
        pass


SILENT: StageProgress = Silent()
