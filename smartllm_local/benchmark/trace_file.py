"""A task's ``trace.json``: what its execution did, written beside its plan for the run viewer.

The results line keeps the metrics; this keeps how they came about: every action with its tick,
sub-task, robots, outcome and where the robots and the object were after it, each goal condition met
or not, and the floor (reachable cells, the robots' starts, the fixed objects) to draw them on.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..executor import Execution
from ..files import write_json
from ..scoring import Scores

TRACE = "trace.json"


def trace_record(execution: Execution, scores: Scores, floor_plan: str, robots: Sequence[int]) -> dict[str, Any]:
    """The trace file's content (``execute --trace``'s fields, the conditions and the layout)."""
    return {"floor_plan": floor_plan, "robots": list(robots), "transitions": execution.transitions,
            "ticks": execution.ticks, "truncated": execution.truncated,
            "starts": [list(s) for s in execution.starts],
            "actions": [e.as_dict() for e in execution.trace],
            "conditions": [{"condition": text, "met": ok} for text, ok in scores.conditions],
            "layout": execution.layout}


def write_trace(folder: Path, execution: Execution, scores: Scores, floor_plan: str,
                robots: Sequence[int]) -> Path:
    return write_json(Path(folder) / TRACE, trace_record(execution, scores, floor_plan, robots))
