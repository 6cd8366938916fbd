"""A run folder read into the one JSON object the viewer page embeds.

A benchmark run (``benchmark run --out``: run.json, results.jsonl, a folder per task) and a
``plan --out`` folder (result.json, the stages, trace.json with ``--execute``) are both read from
their files alone. What a folder lacks is said in the data (``missing``), never guessed: a task not
scored yet, a task whose plan did not run, a run written before traces were kept.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ...benchmark.results import METRICS, STAGE_NAMES, bending, category_groups, metric_mean, refusals, stage_costs
from ...benchmark.run_store import RECORD, RESULTS, RUN_FILE
from ...errors import SmartLLMError, UserError
from ..runs import load_run
from .tasks import Texts, read_task

HINT = "give the --out folder of a `smartllm-local benchmark run` or of a `smartllm-local plan`"
STAGES = (*STAGE_NAMES, "goal")


def load_view(folder: str | Path) -> dict[str, Any]:
    """Read a benchmark run folder or a ``plan --out`` folder into the viewer's data.

    Raises:
        UserError: the folder is missing, holds neither kind of run, holds one run per seed, or its
            run.json or result.json cannot be read.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise UserError(f"{folder} is not a folder: {HINT}")
    if (folder / RUN_FILE).is_file():
        return _benchmark_view(folder)
    if (folder / "result.json").is_file():
        return _plan_view(folder)
    seeds = sorted(p.name for p in folder.glob("seed-*") if (p / RUN_FILE).is_file())
    if seeds:
        raise UserError(f"{folder} holds one run per seed ({', '.join(seeds)}): view one of them, e.g. "
                        f"smartllm-local view {folder / seeds[0]}")
    raise UserError(f"{folder} is not a run: it has no {RUN_FILE} (a benchmark run) and no result.json "
                    f"(a plan's --out); {HINT}")


def _benchmark_view(folder: Path) -> dict[str, Any]:
    manifest = _read_object(folder / RUN_FILE)
    lines: dict[str, dict[str, Any]] = {}
    if (folder / RESULTS).is_file():
        lines = _results(folder)
    started = sorted(p.name for p in folder.iterdir() if p.is_dir() and p.name not in lines and _has_stages(p))
    texts = Texts()
    team_of = _catalogue(manifest)
    tasks = [read_task(folder / task_id, lines.get(task_id), texts, team_of) for task_id in [*lines, *started]]
    missing = []
    finished = (folder / "summary.txt").is_file()
    if not finished:
        missing.append(f"the run is not finished (still running, or stopped): {len(lines)} task(s) scored so far"
                       + (f", {len(started)} begun and not scored yet" if started else "")
                       + "; the same `benchmark run` command resumes it, and `view` again shows what it adds")
    if lines and not any(t["trace"] for t in tasks):
        missing.append("no task has a trace.json (the run was made before traces were kept, or no plan ran): "
                       "the timelines and maps are empty")
    identity = manifest.get("identity", {})
    return {"kind": "benchmark", "folder": str(folder), "label": _label(folder), "finished": finished,
            "started": manifest.get("started"), "model": identity.get("model", {}).get("name"),
            "method": identity.get("arguments", {}).get("method") or "smartllm",
            "arguments": identity.get("arguments", {}), "versions": identity.get("versions", {}),
            "summary": summary(list(lines.values())), "missing": missing, "tasks": tasks,
            "floors": _floors(tasks), "texts": texts.table}


def _plan_view(folder: Path) -> dict[str, Any]:
    result = _read_object(folder / "result.json")
    texts = Texts()
    team_of = _catalogue({})
    task = read_task(folder, None, texts, team_of, plan_result=result)
    missing = [] if task["trace"] else ["the plan was not executed (plan --execute --out writes trace.json): no "
                                        "timeline, map or goal conditions"]
    return {"kind": "plan", "folder": str(folder), "label": folder.name, "finished": True, "started": None,
            "model": result.get("model"), "method": "smartllm", "arguments": {}, "versions": {},
            "summary": None, "missing": missing,  # one task: its own metrics are the summary
            "tasks": [task], "floors": _floors([task]), "texts": texts.table}


def summary(lines: list[dict[str, Any]]) -> dict[str, Any]:
    """Table I's rows (per category, the feasible tasks' mean metrics), the infeasible tasks' refusals, the
    bending measure and the time per stage, from the results lines alone (as the report computes them)."""
    rows = []
    for name, group in category_groups(lines):
        rows.append({"category": name, "tasks": len(group), "errors": sum(1 for x in group if x.get("error")),
                     "refused": sum(1 for x in group if x.get("refused")),
                     **{m: metric_mean(group, m) for m in METRICS}})
    return {"metrics": list(METRICS), "rows": rows, "infeasible": refusals(lines, feasible=False),
            "bending": bending(lines), "stages": stage_costs(lines)}


def _results(folder: Path) -> dict[str, dict[str, Any]]:
    """The run's results lines, read as the report reads them (a line cut short by a kill is left out)."""
    try:
        return {line["id"]: dict(line) for line in load_run(folder).seeds[0]}
    except UserError:  # no scored task yet: the page says so
        return {}


def _has_stages(task_folder: Path) -> bool:
    return any((task_folder / stage / RECORD).is_file() for stage in STAGES) or (task_folder / "result.json").is_file()


def _read_object(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise UserError(f"cannot read {path}: {exc}; {HINT}") from exc
    if not isinstance(data, dict):
        raise UserError(f"{path} is not a JSON object: {HINT}")
    return data


def _label(folder: Path) -> str:
    """The folder's name; a seed's run (``DIR/seed-3``) is named with its parent's."""
    folder = folder.resolve()
    return f"{folder.parent.name}/{folder.name}" if folder.name.startswith("seed-") else folder.name or str(folder)


def _catalogue(manifest: Mapping[str, Any]) -> dict[int, dict[str, Any]]:
    """The run's robots by id (name, skills, mass), from its domain and catalogue where they can still be
    read; {} where not (the viewer then shows the ids alone)."""
    from ...domain import load_domain
    from ...worlds import with_catalogue

    arguments = manifest.get("identity", {}).get("arguments", {})
    try:
        domain = with_catalogue(load_domain(arguments.get("domain")), arguments.get("catalogue"))
    except (SmartLLMError, OSError, ValueError):
        return {}
    return {rid: {"id": rid, "name": r.name, "skills": sorted(r.skills), "mass": r.mass_capacity,
                  "kind": r.kind} for rid, r in domain.catalogue.robots.items()}


def _floors(tasks: list[dict[str, Any]]) -> dict[str, Any]:
    """Each floor plan's reachable cells and fixed objects, once (the tasks on it share them)."""
    floors: dict[str, Any] = {}
    for task in tasks:
        layout = task.pop("layout", None)
        if layout and task["floor_plan"] not in floors:
            floors[task["floor_plan"]] = {"cells": layout.get("cells", []), "landmarks": layout.get("landmarks", [])}
    return floors


__all__ = ["load_view", "summary"]
