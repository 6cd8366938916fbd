"""The report's figures (matplotlib, drawn off-screen): per-category bars for each metric, with the
standard deviation over seeds as error bars, and the time each stage takes."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # no display: files only, on any machine

import matplotlib.pyplot as plt  # noqa: E402  (after choosing the backend)

from ..benchmark.results import METRICS, STAGE_NAMES, mean_sd, stage_costs
from .runs import Run  # noqa: E402
from .tables import categories, per_seed  # noqa: E402


def metric_bars(runs: Sequence[Run], path: Path) -> Path:
    """One panel per metric: a group of bars per category, a bar per run; error bars where a run has
    several seeds."""
    cats = categories(runs) + ["all feasible"]
    figure, axes = plt.subplots(2, 3, figsize=(15, 8), sharey=True)
    width = 0.8 / len(runs)
    for axis, metric in zip(axes.flat, METRICS):
        for k, run in enumerate(runs):
            found = [mean_sd(per_seed(run, c, metric)) for c in cats]
            means = [f[0] if f else 0.0 for f in found]
            errors = [f[1] if f and len(run.seeds) > 1 else 0.0 for f in found]
            axis.bar([x + (k - (len(runs) - 1) / 2) * width for x in range(len(cats))], means, width,
                     yerr=errors if any(errors) else None, capsize=3, label=run.label)
        axis.set_title(metric)
        axis.set_xticks(range(len(cats)), cats, rotation=20)
        axis.set_ylim(0, 1.05)
        axis.grid(axis="y", alpha=0.3)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    figure.legend(handles, labels, loc="lower center", ncol=min(3, len(runs)), frameon=False)
    figure.tight_layout(rect=(0, 0.04 + 0.03 * ((len(runs) - 1) // 3), 1, 1))
    return _save(figure, path)


def stage_times(runs: Sequence[Run], path: Path) -> Path:
    """Each stage's and execution's share of a task's mean seconds, one stacked bar per run."""
    parts = [*STAGE_NAMES, "execution"]
    figure, axis = plt.subplots(figsize=(10, 1.5 + 0.6 * len(runs)))
    left = [0.0] * len(runs)
    costs = [stage_costs(run.lines) for run in runs]
    for part in parts:
        seconds = [cost.get(part, {}).get("share", 0.0) for cost in costs]
        axis.barh(range(len(runs)), seconds, left=left, label=part)
        left = [a + b for a, b in zip(left, seconds)]
    axis.set_yticks(range(len(runs)), [run.label for run in runs])
    axis.invert_yaxis()
    axis.set_xlabel("seconds per task (mean)")
    axis.legend(loc="upper left", bbox_to_anchor=(1.01, 1), fontsize="small")
    figure.tight_layout()
    return _save(figure, path)


def _save(figure: plt.Figure, path: Path) -> Path:
    tmp = path.with_name(f".{path.name}.tmp")
    figure.savefig(tmp, dpi=120, format="png")
    plt.close(figure)
    tmp.replace(path)  # a figure is never left half-written
    return path
