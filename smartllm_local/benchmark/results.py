"""Results lines (one JSON object per scored task, ``results.jsonl``) and what is computed from them.

Every table this project prints or writes, from a run's summary.txt to the
report's Tables I-III, is computed here from the lines alone, so a number can
be recomputed by anyone holding the file. A task that produced no run (an
error, a refusal) scores 0 on every metric; a metric a run cannot be judged on
(no goal conditions, no ground-truth transitions: some imported tasks) is left
out of that metric's mean rather than counted as 0, and a mean with nothing to
average is None (printed n/a).
"""

from __future__ import annotations

import json
import statistics
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from .tasks import CATEGORIES

METRICS = ("SR", "TCR", "GCR", "RU", "Exe", "Speed")
PAPER_METRICS = METRICS[:5]
STAGE_NAMES = ("goal", "decomposition", "coalition", "allocation")
REFUSERS = ("model", "grammar", "goal check", "rule", "planner")

Line = Mapping[str, Any]


def parse_results(text: str) -> tuple[dict[str, dict[str, Any]], int]:
    """A results file's lines by task id, and how much of ``text`` they take: reading stops at the
    first line that is not a whole JSON object (a line cut short by a kill)."""
    found: dict[str, dict[str, Any]] = {}
    good = 0
    for line in text.splitlines(keepends=True):
        try:
            data = json.loads(line) if line.endswith("\n") else None
        except ValueError:
            data = None
        if not isinstance(data, dict) or "id" not in data:
            break
        found[data["id"]] = data
        good += len(line)
    return found, good


def read_results(path: str | Path) -> dict[str, dict[str, Any]]:
    """A results file's whole lines by task id (read-only)."""
    return parse_results(Path(path).read_text(encoding="utf-8"))[0]


def category_groups(lines: Sequence[Line]) -> list[tuple[str, list[Line]]]:
    """The feasible lines per category (in the paper's order), then all of them as "all feasible"."""
    feasible = [line for line in lines if line["feasible"]]
    groups = [(c, [line for line in feasible if line["category"] == c]) for c in (*CATEGORIES, "uncategorized")]
    return [(name, group) for name, group in [*groups, ("all feasible", feasible)] if group]


def metric_mean(group: Sequence[Line], metric: str) -> float | None:
    """A metric's mean over a group's lines: a line without it (an error, a refusal) counts 0, one
    whose run cannot be judged on it (None) is left out."""
    known = [v for v in (line.get(metric, 0.0) for line in group) if v is not None]
    return sum(known) / len(known) if known else None


def mean_sd(values: Sequence[float]) -> tuple[float, float] | None:
    """Mean and sample standard deviation (0 for one value); None for no values."""
    if not values:
        return None
    return statistics.fmean(values), statistics.stdev(values) if len(values) > 1 else 0.0


def refusals(lines: Sequence[Line], feasible: bool) -> dict[str, int]:
    """Of the feasible (or infeasible) lines: how many, how many refused, and who refused them."""
    group = [line for line in lines if line["feasible"] == feasible]
    refused = [line for line in group if line["refused"]]
    by = Counter(line.get("refused_by") or "model" for line in refused)
    return {"tasks": len(group), "refused": len(refused), **{f"by {k}": by[k] for k in REFUSERS},
            "errors": sum(1 for line in group if line.get("error"))}


def stage_costs(lines: Sequence[Line]) -> dict[str, dict[str, float]]:
    """Per stage (and "execution", and "task" for the whole): mean seconds, prompt tokens, prompt tokens
    reused from a kept state (0 in lines written before reuse was recorded) and generated tokens over the
    lines that reached it, and "share": its seconds over all lines (the shares add
    up to a task's mean seconds)."""
    costs: dict[str, dict[str, float]] = {}
    for stage in STAGE_NAMES:
        ran = [line["tokens"][stage] for line in lines if stage in line.get("tokens", {})]
        if ran:
            costs[stage] = {"tasks": len(ran), "share": sum(r["seconds"] for r in ran) / len(lines),
                            **{k: statistics.fmean(float(r.get(k, 0)) for r in ran)
                               for k in ("seconds", "prompt", "reused", "generated")}}
    executed = [line["seconds"] - sum(t["seconds"] for t in line.get("tokens", {}).values())
                for line in lines if line.get("Exe") is not None and "ticks" in line]
    if executed:
        costs["execution"] = {"tasks": len(executed), "seconds": statistics.fmean(executed),
                              "share": sum(executed) / len(lines)}
    if lines:
        costs["task"] = {"tasks": len(lines), "seconds": statistics.fmean(line["seconds"] for line in lines),
                         "total": sum(line["seconds"] for line in lines)}
    return costs


def bending(lines: Sequence[Line]) -> dict[str, dict[str, float | int | None]]:
    """How far the grammar bent the model, per stage, over the lines that recorded it: the share of the model's
    choices where its likeliest token was refused, the mean log-probability of what it chose (under the
    unconstrained model), and the lines the planner completed after the model ended the sequence."""
    found: dict[str, dict[str, float | int | None]] = {}
    for stage in STAGE_NAMES:
        ran = [line["tokens"][stage] for line in lines if "choices" in line.get("tokens", {}).get(stage, {})]
        choices = sum(r["choices"] for r in ran)
        if choices:
            found[stage] = {"choices": choices, "refused_share": sum(r["refused"] for r in ran) / choices,
                            "mean_logprob": sum(r["logprob"] for r in ran) / choices,
                            "completed_lines": sum(r.get("completed_lines", 0) for r in ran)}
    return found


def bending_line(lines: Sequence[Line]) -> str:
    """The bending measure as summary.txt gives it (empty where no line recorded it)."""
    parts = [f"{stage} {b['refused_share']:.1%} of {b['choices']:,} refused, log-prob {b['mean_logprob']:.3f}"
             for stage, b in bending(lines).items()]
    return "model's likeliest token refused: " + "; ".join(parts) if parts else ""


def summary_table(lines: Sequence[Line]) -> str:
    """Mean metrics per category (feasible tasks) and the refusal rate on infeasible ones."""
    rows = [f"{'category':<14}{'tasks':>6}{'errors':>7}" + "".join(f"{m:>7}" for m in METRICS) + f"{'refused':>9}"]
    for name, group in category_groups(lines):
        errors = sum(1 for line in group if line.get("error"))
        means = [metric_mean(group, metric) for metric in METRICS]
        refused = sum(1 for line in group if line["refused"])
        rows.append(f"{name:<14}{len(group):>6}{errors:>7}" + "".join(
            f"{'n/a' if m is None else f'{m:.2f}':>7}" for m in means) + f"{refused:>9}")
    counts = refusals(lines, feasible=False)
    if counts["tasks"]:
        who = ", ".join(f"{counts[f'by {k}']} by {k}" for k in REFUSERS
                        if counts[f"by {k}"] or k in ("model", "grammar"))
        rows.append(f"{'infeasible':<14}{counts['tasks']:>6}{counts['errors']:>7}"
                    f"   correctly refused {counts['refused']}/{counts['tasks']} ({who})")
    extra = [line for line in (bending_line(lines), repairs_line(lines), executable_line(lines), candidates_line(lines))
             if line]
    return "\n".join(rows + extra)


def repairs_line(lines: Sequence[Line]) -> str:
    """What the planner wrote into the decompositions: repairs (its steps before a model's call, and the calls it
    could not enable), plans ended at the stated goals, plans it finished (and of those, folded into the model's last
    sub-task), errands and idle steps it took out, sub-tasks it joined, things kept in hand it put away ("" where it
    did nothing)."""
    ran = [line["tokens"]["decomposition"] for line in lines if "decomposition" in line.get("tokens", {})]
    repairs, tasks = sum(r.get("repairs", 0) for r in ran), sum(bool(r.get("repairs")) for r in ran)
    missed, ended = sum(r.get("unrepaired", 0) for r in ran), sum(bool(r.get("ended_at_goals")) for r in ran)
    finished, folded = sum(bool(r.get("finished")) for r in ran), sum(bool(r.get("folded")) for r in ran)
    idle, idle_tasks = sum(r.get("idle_steps", 0) for r in ran), sum(bool(r.get("idle_steps")) for r in ran)
    errands, errand_tasks = sum(r.get("errands", 0) for r in ran), sum(bool(r.get("errands")) for r in ran)
    joined, joined_tasks = sum(r.get("joined", 0) for r in ran), sum(bool(r.get("joined")) for r in ran)
    put, put_tasks = sum(r.get("put_away", 0) for r in ran), sum(bool(r.get("put_away")) for r in ran)
    if not (repairs or missed or ended or finished or idle or errands or joined or put):
        return ""
    return (f"planner in the decomposition: {repairs} repair(s) in {tasks} task(s), {missed} call(s) it could not "
            f"enable taken back; {ended} plan(s) ended at the stated goals; {finished} finished by its last "
            f"sub-task ({folded} in the model's last); {errands} errand line(s) taken out in {errand_tasks} task(s); "
            f"{idle} idle line(s) taken out in {idle_tasks} task(s); {joined} sub-task(s) joined to one before in "
            f"{joined_tasks} task(s); {put} line(s) putting a thing kept in hand where it goes in {put_tasks} "
            f"task(s)")


def executable_line(lines: Sequence[Line]) -> str:
    """What the planner changed in the allocations for every call to succeed when the team runs them (threads in
    turn, calls taken out; "" where it changed nothing)."""
    ran = [line["tokens"]["allocation"].get("executable", 0)
           for line in lines if "allocation" in line.get("tokens", {})]
    if not any(ran):
        return ""
    return f"planner in the allocation: {sum(ran)} change(s) in {sum(map(bool, ran))} task(s) so that no call fails"


def candidates_line(lines: Sequence[Line]) -> str:
    """Over the feasible tasks that wrote several candidates: how many any candidate's dry run meets the task's
    goals in (pass@N, the ceiling of choosing), and how many the chosen one's does ("" where none did)."""
    ran = [line for line in lines if line["feasible"] and line.get("candidates")]
    if not ran:
        return ""
    n = max(len(line["candidates"]) for line in ran)
    chosen = sum(any(c["chosen"] and c["meets_task_goals"] for c in line["candidates"]) for line in ran)
    passed = sum(bool(line.get("pass_at_n")) for line in ran)
    return (f"candidates (dry runs meeting the task's goals, measured only): pass@{n} {passed}/{len(ran)}, "
            f"chosen {chosen}/{len(ran)}")


def variability_table(runs: Sequence[Sequence[Line]]) -> str:
    """The paper's Table II: per category and metric, the mean and standard deviation over runs
    (seeds) of each run's category mean; and the refusal rate of infeasible tasks likewise."""
    rows = [f"{'category':<14}{'tasks':>6}{'runs':>5}" + "".join(f"{m:>12}" for m in METRICS)]
    per_run = [dict(category_groups(lines)) for lines in runs]
    for name, group in category_groups(runs[0]):
        cells = []
        for metric in METRICS:
            values = [v for v in (metric_mean(groups.get(name, []), metric) for groups in per_run) if v is not None]
            cells.append(_spread(values))
        rows.append(f"{name:<14}{len(group):>6}{len(runs):>5}" + "".join(f"{c:>12}" for c in cells))
    infeasible = [[line for line in lines if not line["feasible"]] for lines in runs]
    if infeasible[0]:
        rates = [sum(line["refused"] for line in group) / len(group) for group in infeasible if group]
        rows.append(f"{'infeasible':<14}{len(infeasible[0]):>6}{len(runs):>5}   refused {_spread(rates)}")
    return "\n".join(rows)


def _spread(values: Sequence[float]) -> str:
    found = mean_sd(values)
    return "n/a" if found is None else f"{found[0]:.2f}±{found[1]:.2f}"
