"""The report's tables, laid out as SMART-LLM's: Table I (category × SR/TCR/GCR/RU/Exe), Table II
(mean ± standard deviation over seeds), Table III (ablations); then refusals, efficiency, and time
and tokens per stage. Each is rendered as Markdown and as CSV with the same rows and columns."""

from __future__ import annotations

import csv
import io
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from ..benchmark.failures import REFUSED, SHOWN, run_failures
from ..benchmark.results import (
    PAPER_METRICS,
    REFUSERS,
    STAGE_NAMES,
    bending,
    category_groups,
    mean_sd,
    metric_mean,
    refusals,
    stage_costs,
)
from ..benchmark.tasks import CATEGORIES
from .runs import Run

Cell = Any  # str, int, float, None (n/a) or (mean, sd)


@dataclass
class Table:
    name: str  # the CSV file's stem
    title: str
    columns: list[str]
    rows: list[list[Cell]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def markdown(self) -> str:
        labels = self._labels()
        lines = [f"## {self.title}", "", "| " + " | ".join(self.columns) + " |",
                 "|" + "|".join("---" if k < labels else "---:" for k in range(len(self.columns))) + "|"]
        lines += ["| " + " | ".join(_text(cell) for cell in row) + " |" for row in self.rows]
        return "\n".join(lines + [""] + [f"{note}  " for note in self.notes]).rstrip() + "\n"

    def csv(self) -> str:
        """The same table with numbers unrounded; a mean ± sd column becomes two ("X mean", "X sd")."""
        spread = [any(isinstance(row[k], tuple) for row in self.rows) for k in range(len(self.columns))]
        header = [part for k, c in enumerate(self.columns) for part in ([f"{c} mean", f"{c} sd"] if spread[k] else [c])]
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(header)
        for row in self.rows:
            cells: list[Any] = []
            for k, cell in enumerate(row):
                if spread[k]:
                    cells += list(cell) if isinstance(cell, tuple) else ["", ""]
                else:
                    cells.append("" if cell is None else cell)
            writer.writerow(cells)
        return buffer.getvalue()

    def _labels(self) -> int:
        """How many leading columns are labels (left-aligned) rather than numbers."""
        for k in range(len(self.columns)):
            if any(isinstance(row[k], (int, float, tuple)) or row[k] is None for row in self.rows):
                return k
        return len(self.columns)


def _text(cell: Cell) -> str:
    if cell is None:
        return "n/a"
    if isinstance(cell, tuple):
        return f"{cell[0]:.2f} ± {cell[1]:.2f}"
    if isinstance(cell, float):
        return f"{cell:.2f}"
    return str(cell)


def categories(runs: Sequence[Run]) -> list[str]:
    """The categories (with feasible tasks) any run has, in the paper's order."""
    present = {name for run in runs for name, _ in category_groups(run.lines)}
    return [c for c in (*CATEGORIES, "uncategorized") if c in present]


def per_seed(run: Run, category: str, metric: str) -> list[float]:
    """The category's mean of ``metric`` in each of the run's seeds that can be judged on it."""
    values = []
    for lines in run.seeds:
        groups = dict(category_groups(lines))
        value = metric_mean(groups.get(category, []), metric)
        if value is not None:
            values.append(value)
    return values


def _mean_over_seeds(run: Run, category: str, metric: str) -> float | None:
    found = mean_sd(per_seed(run, category, metric))
    return None if found is None else found[0]


def _who(run: Run) -> list[Cell]:
    return [run.method, run.model, run.variant or "-"]


def table_one(runs: Sequence[Run]) -> Table:
    cats = categories(runs)
    table = Table("table1", "Table I: success by task category",
                  ["Method", "Model", "Variant", "Tasks", "Seeds"] + [f"{c} {m}" for c in cats for m in PAPER_METRICS])
    for run in runs:
        for tasks, part in run.parts():
            table.rows.append(_who(run) + [tasks, len(run.seeds)] + [
                _mean_over_seeds(part, c, m) for c in cats for m in PAPER_METRICS])
    table.notes.append("Means over each category's feasible tasks (a task that errored or was refused scores 0); "
                       "with several seeds, the mean of the seeds' means.")
    table.notes += _split_notes(runs)
    return table


def _split_notes(runs: Sequence[Run]) -> list[str]:
    """What the Tasks column's halves are, where a row gives one."""
    files = sorted({run.manifests[0].get("split", {}).get("file", "") for run in runs
                    if any(tasks != "all" for tasks, _ in run.parts())})
    if not files:
        return []
    return [f"Tasks: a half of the development/test split ({', '.join(files)}) is the feasible tasks it puts "
            "there and every infeasible task; prompts and settings are chosen on the dev half only, so the test "
            "half's figures were not tuned on its own tasks. all: every task the run holds."]


def table_two(runs: Sequence[Run]) -> Table | None:
    seeded = [run for run in runs if len(run.seeds) > 1]
    if not seeded:
        return None
    cats = categories(seeded)
    table = Table("table2", "Table II: variability over seeds (mean ± standard deviation)",
                  ["Method", "Model", "Variant", "Tasks", "Seeds"] + [f"{c} {m}" for c in cats for m in PAPER_METRICS])
    for run in seeded:
        for tasks, part in run.parts():
            table.rows.append(_who(run) + [tasks, len(run.seeds)] + [
                mean_sd(per_seed(part, c, m)) for c in cats for m in PAPER_METRICS])
    table.notes.append("Each cell: the mean and the sample standard deviation, over the seeds, of the category's "
                       "mean.")
    table.notes += _split_notes(seeded)
    return table


def table_three(runs: Sequence[Run]) -> Table | None:
    """One row per ablation run, beside the full runs of the same model and method."""
    if not any(run.ablation != "full" for run in runs):
        return None
    studied = {(run.model, run.method) for run in runs if run.ablation != "full"}
    rows = [run for run in runs if (run.model, run.method) in studied]
    common = frozenset.intersection(*(run.task_ids for run in rows))
    if any(run.task_ids != common for run in rows):  # compare like with like: the tasks all rows ran
        rows = [run.restricted(common) for run in rows]
    table = Table("table3", "Table III: ablations (feasible tasks of every category)",
                  ["Ablation", "Model", "Method", "Seeds", *PAPER_METRICS, "s/task"])
    for run in rows:
        costs = stage_costs(run.lines)
        table.rows.append([run.ablation, run.model, run.method, len(run.seeds)]
                          + [_mean_over_seeds(run, "all feasible", m) for m in PAPER_METRICS]
                          + [costs.get("task", {}).get("seconds")])
    table.notes.append("Left out of the prompts: comments (the examples' comments), summary (the decomposition's "
                       "closing summary), coalition (the coalition-formation stage).")
    if any(len(run.task_ids) != len(common) for run in runs if (run.model, run.method) in studied):
        tasks = "task" if len(common) == 1 else "tasks"
        table.notes.append(f"Over the {len(common)} {tasks} every row's run has (some runs have more).")
    return table


def refusal_table(runs: Sequence[Run]) -> Table:
    table = Table("refusals", "Refusals: infeasible tasks refused (and feasible ones), and who refused",
                  ["Method", "Model", "Variant", "Infeasible", "Refused", *(f"by {k}" for k in REFUSERS),
                   "Feasible", "Feasible refused", "Errors"])
    for run in runs:
        bad, good = refusals(run.lines, feasible=False), refusals(run.lines, feasible=True)
        table.rows.append(_who(run) + [bad["tasks"], bad["refused"], *(bad[f"by {k}"] for k in REFUSERS),
                                       good["tasks"], good["refused"], bad["errors"] + good["errors"]])
    table.notes += [
        "by model: the model chose to refuse; by grammar: the grammar left it no other output (no team of the "
        "robots can do a sub-task it wrote); by goal check: a goal the model stated is out of the team's reach; "
        "by rule: a method without a model (decomp-rule, reference); by "
        "planner: the goal-planner's search proved the goal unreachable for the team.",
        "Counts are summed over seeds."]
    return table


def efficiency_table(runs: Sequence[Run]) -> Table:
    cats = categories(runs) + ["all feasible"]
    table = Table("efficiency", "Efficiency: the paper's RU beside Speed (the reference plan's time over the run's)",
                  ["Method", "Model", "Variant"] + [f"{c} {m}" for c in cats for m in ("RU", "Speed")])
    for run in runs:
        table.rows.append(_who(run) + [_mean_over_seeds(run, c, m) for c in cats for m in ("RU", "Speed")])
    table.notes.append("Speed = min(1, the reference plan's ticks / the run's ticks) for a run that meets every "
                       "goal condition, else 0: a plan that does everything with one robot, one sub-task after "
                       "another, can score RU 1 but not Speed 1.")
    return table


def stage_table(runs: Sequence[Run]) -> Table:
    columns = ["Method", "Model", "Variant", "Tasks"]
    for stage in STAGE_NAMES:
        columns += [f"{stage} s", f"{stage} prompt tok", f"{stage} reused tok", f"{stage} gen tok"]
    table = Table("stages", "Time and tokens per stage (means per task that reached the stage)",
                  columns + ["execution s", "s/task", "total h"])
    for run in runs:
        costs = stage_costs(run.lines)
        row = _who(run) + [len(run.lines)]
        for stage in STAGE_NAMES:
            cost = costs.get(stage, {})
            row += [cost.get("seconds"), _whole(cost.get("prompt")), _whole(cost.get("reused")),
                    _whole(cost.get("generated"))]
        task = costs.get("task", {})
        total = task.get("total")
        row += [costs.get("execution", {}).get("seconds"), task.get("seconds"),
                None if total is None else total / 3600]
        table.rows.append(row)
    table.notes += ["Seconds are each task's own (its stages and its execution), summed over seeds for the "
                    "total; a stage a method does not have is n/a.",
                    "Reused: prompt tokens (the stage's examples) whose key/value state was kept from an "
                    "earlier task or run rather than evaluated."]
    return table


def bending_table(runs: Sequence[Run]) -> Table:
    columns = ["Method", "Model", "Variant"]
    for stage in STAGE_NAMES:
        columns += [f"{stage} refused %", f"{stage} log-prob", f"{stage} completed"]
    table = Table("bending", "How far the grammar bent the model: its likeliest token refused, and the mean "
                  "log-probability of what it chose", columns)
    for run in runs:
        found = bending(run.lines)
        row = _who(run)
        for stage in STAGE_NAMES:
            b = found.get(stage, {})
            share = b.get("refused_share")
            row += [None if share is None else 100 * share, b.get("mean_logprob"), b.get("completed_lines")]
        table.rows.append(row)
    table.notes += ["refused %: the share of the model's own choices (tokens it picked, not text the planner "
                    "forced) where its likeliest token was one the grammar refused; log-prob: the mean "
                    "log-probability of the tokens it picked, under the unconstrained model (free generation "
                    "is the yardstick); completed: lines the planner completed after the model ended the "
                    "sequence. n/a where a backend does not measure them (servers) or a method has no stage."]
    return table


def failure_table(runs: Sequence[Run]) -> Table:
    """Where each run's feasible tasks failed, by category: one kind each (benchmark.failures)."""
    refusers = [k for k in REFUSERS if k != "planner"]
    kinds = [f"{REFUSED} by {k}" for k in refusers] + [k for k in SHOWN if k != REFUSED]
    table = Table("failures", "Where each method fails: the feasible tasks not succeeded on, by kind of failure",
                  ["Method", "Model", "Variant", "Tasks", "Category", "Feasible", "Failed", *kinds])
    for run in runs:
        found = [f for folder in run.run_folders for f in run_failures(folder)]
        for tasks, part in run.parts():
            ids = {line["id"] for line in part.lines}
            for category, group in category_groups(part.lines):
                counts = Counter(f.counted for f in found
                                 if f.id in ids and category in ("all feasible", f.category))
                table.rows.append(_who(run) + [tasks, category, len(group), sum(counts.values()),
                                               *(counts[k] for k in kinds)])
    table.notes += [
        "Each failed task counts once, as the first of these that applies (docs/metrics.md defines them): a goal "
        "stated and met that is not the instruction's, a wrong goal stated (a condition of the task's missed, or "
        "one added that is false at the end), refused (and by whom), no plan found (refused by the planner, its "
        "time limit, an error), an action failed in execution, every action succeeded but the plan fell short of "
        "the goal, or the goal met with extra work (RU < 1).",
        "Counts are summed over seeds."]
    return table


def _whole(value: float | None) -> int | None:
    return None if value is None else round(value)


def all_tables(runs: Sequence[Run]) -> list[Table]:
    tables = [table_one(runs), table_two(runs), table_three(runs), refusal_table(runs), efficiency_table(runs),
              failure_table(runs), stage_table(runs), bending_table(runs)]
    return [table for table in tables if table is not None]
