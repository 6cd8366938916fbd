"""One error hierarchy for the whole project.

A :class:`UserError` is a problem the person running the tool can fix (a bad
file, an unknown floor plan, a missing model); its message says what is wrong,
where, and what to do, and the CLI prints it without a traceback and exits 2.
Everything else deriving from :class:`SmartLLMError` is a failure of a part
(the AI2-THOR process died, a model crashed) and exits 1.
"""

from __future__ import annotations


class SmartLLMError(Exception):
    """Base class of every error this package raises on purpose."""


class UserError(SmartLLMError):
    """A problem with the input that the user can fix."""


class UnknownFloorPlanError(UserError, ValueError):
    """A floor plan name or number that is not one of the 120 iTHOR scenes."""


class SceneDataError(UserError):
    """The AI2-THOR scene metadata is missing or unreadable."""


class WorldError(SmartLLMError, RuntimeError):
    """The AI2-THOR process (stand-in or Unity build) failed or stopped answering."""


class CatalogueError(UserError):
    """A robot catalogue file or a robot id is invalid."""


class PlanError(UserError):
    """A plan failed to parse or validate; carries every problem found."""

    def __init__(self, problems: list[tuple[int, int, str]], source_name: str = "<plan>"):
        self.problems = problems
        self.source_name = source_name
        lines = [f"{source_name}:{line}:{col}: {message}" for line, col, message in problems]
        super().__init__("\n".join(lines) if lines else f"{source_name}: invalid plan")


class TaskFileError(UserError):
    """A benchmark task file (or goal file) is malformed."""


class ModelError(UserError):
    """A model path is missing, unreadable or of the wrong kind."""


class BackendUnavailableError(UserError):
    """An optional dependency needed by the chosen backend is not installed."""


class GrammarMismatchError(SmartLLMError):
    """The grammar engine (llama.cpp's, llguidance) let through text the planner's own grammar does not
    allow, or refused text it forces: the two disagree, and no plan may be built on either."""

    def __init__(self, text: str, why: str, stage: str = ""):
        self.text, self.why, self.stage = text, why, stage
        where = f"{stage} stage: " if stage else ""
        super().__init__(f"{where}the grammars disagree about {text!r}: {why}")

    def in_stage(self, stage: str) -> GrammarMismatchError:
        """The same error, naming the stage it happened in."""
        return GrammarMismatchError(self.text, self.why, stage)
