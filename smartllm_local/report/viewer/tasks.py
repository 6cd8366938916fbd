"""One task's folder read for the viewer: its stages, its plan, its trace and why it failed."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ...benchmark.trace_file import TRACE
from ...planner.pipeline import STAGE_OUTPUTS

STAGE_ORDER = ("goal", "decomposition", "coalition", "allocation")  # the goal check states the goals first


class Texts:
    """Long texts (prompts, grammars) kept once in the page: every task's prompt repeats the same examples."""

    def __init__(self) -> None:
        self.table: list[str] = []
        self._index: dict[str, int] = {}

    def add(self, text: str | None) -> int | None:
        if not text:
            return None
        if text not in self._index:
            self._index[text] = len(self.table)
            self.table.append(text)
        return self._index[text]


def read_task(folder: Path, line: Mapping[str, Any] | None, texts: Texts, team_of: Mapping[int, dict[str, Any]],
              *, plan_result: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """A task as the viewer shows it. ``line`` is its results line (None: not scored yet); ``plan_result`` is a
    plan folder's result.json (read from the task folder otherwise)."""
    result = plan_result if plan_result is not None else _json(folder / "result.json") or {}
    outcome = dict(line) if line is not None else (result.get("outcome") or _plan_outcome(result))
    trace = _json(folder / TRACE)
    robots = list(result.get("robots") or (trace or {}).get("robots") or [])
    task: dict[str, Any] = {
        "id": (line or {}).get("id") or outcome.get("id") or folder.name,
        "category": outcome.get("category") or "",
        "feasible": outcome.get("feasible", True),
        "instruction": result.get("instruction") or "",
        "floor_plan": result.get("floor_plan") or (trace or {}).get("floor_plan") or "",
        "team": [team_of.get(r, {"id": r, "name": f"robot{r}", "skills": [], "mass": None}) for r in robots],
        "outcome": outcome or None,
        "refusal": result.get("refusal"),
        "error": outcome.get("error") or result.get("error") or "",
        "notices": result.get("notices") or [],
        "stages": _stages(folder, texts),
        "allocated": _text(folder / "allocated.py"),
        "trace": None, "layout": None,
    }
    if trace is not None:
        task["layout"] = trace.get("layout")
        task["trace"] = {k: trace.get(k) for k in ("actions", "conditions", "ticks", "transitions", "starts",
                                                     "truncated")}
        task["start"] = (trace.get("layout") or {}).get("start") or []
    task["status"] = task_status(task, scored=line is not None or plan_result is not None)
    task["why"] = why(task)
    return task


def _plan_outcome(result: Mapping[str, Any]) -> dict[str, Any]:
    """A plan folder's metrics (``plan --execute``), shaped as a results line."""
    metrics = result.get("metrics")
    if not metrics:
        return {}
    return {**metrics, "feasible": True, "refused": result.get("refusal") is not None,
            "success": metrics.get("SR") == 1.0}


def _stages(folder: Path, texts: Texts) -> list[dict[str, Any]]:
    """Each stage the task reached, from its written files, or (a stage saved but the task not yet scored)
    from its saved record."""
    stages = []
    for name in STAGE_ORDER:
        where = folder / name
        record = _json(where / "record.json") or {}
        if not where.is_dir() and not (folder / STAGE_OUTPUTS[name]).is_file():
            continue
        timings = _json(where / "timings.json") or {k: record.get(k) for k in ("prompt_tokens", "generated_tokens",
                                                                                 "seconds") if k in record}
        grammar = _text(where / "grammar.gbnf") or "\n".join(record.get("grammars") or [])
        stages.append({
            "name": name,
            "output": _text(folder / STAGE_OUTPUTS[name]) or record.get("output", ""),
            "prompt": texts.add(_text(where / "prompt.txt") or record.get("prompt")),
            "grammar": texts.add(grammar),
            "raw": _text(where / "raw_output.txt") or record.get("raw", ""),
            "refusal": record.get("refusal"), "error": record.get("error", ""),
            "timings": timings,
            "candidates": _json(where / "candidates.json") or record.get("candidates") or [],
        })
    return stages


def task_status(task: Mapping[str, Any], *, scored: bool) -> str:
    """success, failed, refused (a feasible task refused, or an infeasible one refused as it should be: see
    ``outcome.success``), error (planning or execution failed) or pending (not scored yet)."""
    if not scored:
        return "pending"
    outcome = task["outcome"] or {}
    if task["error"]:
        return "error"
    if outcome.get("refused") or task["refusal"]:
        return "refused"
    return "success" if outcome.get("success") else "failed"


def why(task: Mapping[str, Any]) -> list[str]:
    """Why the task failed (or what is missing), in the words a researcher looks for first: the error, the
    refusal, the first failed action, the goal conditions left unmet, the transitions."""
    status, outcome, trace = task["status"], task["outcome"] or {}, task["trace"]
    if status == "pending":
        return ["not scored yet: the run has not reached this task's execution"]
    if status == "error":
        return [f"error: {task['error']}"]
    if status == "refused":
        who = outcome.get("refused_by") or "model"
        verdict = ("correctly: the task is infeasible" if not task["feasible"]
                   else "but the task is feasible: a failure")
        return [f"refused by the {who} ({verdict}): {task['refusal'] or ''}".rstrip(": ")]
    if not task["feasible"]:
        return ["the task is infeasible and the plan did not refuse it"]
    reasons = []
    if trace is None:
        return ["no trace.json: the plan's execution was not recorded"] if status != "success" else []
    failed = [a for a in trace.get("actions") or [] if not a.get("success")]
    if failed:
        first = failed[0]
        reasons.append(f"{len(failed)} failed action(s); the first at tick {first['tick']}: "
                       f"{first['skill']}({', '.join(first['objects'])}) by robot(s) "
                       f"{', '.join(map(str, first['robots']))}: {first.get('errorMessage') or 'failed'}")
    unmet = [c["condition"] for c in trace.get("conditions") or [] if not c["met"]]
    if unmet:
        reasons.append("goal conditions not met: " + "; ".join(unmet))
        if not failed:
            reasons.append(f"every one of the plan's {len(trace.get('actions') or [])} action(s) succeeded: the "
                           "plan does not do what the goals need (see its stages)")
    if trace.get("truncated"):
        reasons.append("the run was cut at the executor's tick limit")
    better = [c["candidate"] for c in outcome.get("candidates") or [] if c.get("meets_task_goals") and not c["chosen"]]
    if better and unmet:
        reasons.append(f"candidate(s) {', '.join(map(str, better))} of the decomposition would have met the task's "
                       "goals in the dry run, but another was chosen")
    if outcome.get("RU") is not None and outcome["RU"] < 1 and outcome.get("TCR") == 1:
        reasons.append(f"every goal met, but with {outcome.get('transitions')} transition(s): RU "
                       f"{outcome['RU']:.2f}, so SR 0")
    return reasons


def _json(path: Path) -> Any:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def _text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return ""
