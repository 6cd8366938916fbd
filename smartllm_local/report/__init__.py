"""``benchmark report``: the paper's tables and figures for one or more runs, from their folders alone.

The report is computed from ``results.jsonl`` and ``run.json`` (see
:mod:`smartllm_local.benchmark.results` for how a mean treats errors, refusals and
metrics a task cannot be judged on), and the failures table from the tasks' folders
too (:mod:`smartllm_local.benchmark.failures`), so it can be made again, on any
machine, long after the run: report.md (every table, and what each run was), one
CSV per table, and PNG figures.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from ..errors import UserError
from ..files import check_output_folder, write_atomic
from .runs import Run, load_run
from .tables import Table, all_tables


def write_report(folders: Sequence[str | Path], out: str | Path, *, html: bool = False) -> list[Path]:
    """Read the runs in ``folders`` and write report.md, a CSV per table and the figures into ``out``; with
    ``html``, each run's viewer page too (one per seed of a ``--seeds`` run), linked from report.md.

    Raises:
        UserError: no folder given, a folder holds no readable run, or ``out`` cannot be a folder.
    """
    if not folders:
        raise UserError("give at least one run folder (the --out of a `smartllm-local benchmark run`)")
    out = check_output_folder(Path(out), "--out")
    runs = [load_run(folder) for folder in folders]
    tables = all_tables(runs)
    viewers = _viewers(runs, out) if html else []
    written = [write_atomic(out / "report.md", markdown(runs, tables, [(label, p.name) for label, p in viewers]))]
    written += [path for _, path in viewers]
    written += [write_atomic(out / f"{table.name}.csv", table.csv()) for table in tables]
    from .figures import metric_bars, stage_times  # matplotlib loads only when a report is drawn

    written.append(metric_bars(runs, out / "metrics.png"))
    written.append(stage_times(runs, out / "stages.png"))
    return written


def _viewers(runs: Sequence[Run], out: Path) -> list[tuple[str, Path]]:
    """Write each run's viewer page into ``out`` (a run of several seeds: one per seed), labelled."""
    from .viewer import write_viewer

    pages = []
    for k, run in enumerate(runs, 1):
        for part in run.run_folders:
            label = run.label if part == run.folder else f"{run.label}, {part.name}"
            name = f"viewer-{k}" + ("" if part == run.folder else f"-{part.name}") + ".html"
            pages.append((label, write_viewer(part, out / name)))
    return pages


def markdown(runs: Sequence[Run], tables: Sequence[Table], viewers: Sequence[tuple[str, str]] = ()) -> str:
    parts = ["# Benchmark report", "", "## Runs", ""]
    for run in runs:
        identity = run.manifests[0].get("identity", {})
        model = identity.get("model", {})
        digest = f", sha256 {model['sha256'][:12]}…" if model.get("sha256") else ""
        versions = identity.get("versions", {})
        scored = len(run.seeds[0]) if len(run.seeds) == 1 else "/".join(str(len(s)) for s in run.seeds)
        seeds = ", ".join(str(m.get("identity", {}).get("arguments", {}).get("seed")) for m in run.manifests)
        half = run.arguments.get("split")
        tasks = f" (the {half} half of {run.manifests[0].get('split', {}).get('file')})" if half else ""
        parts.append(f"- **{run.label}**: `{run.folder}`; tasks scored {scored}{tasks}; seed(s) {seeds}; "
                     f"model {model.get('name', '-')}{digest}; smartllm-local {versions.get('smartllm-local')}, "
                     f"llama-cpp-python {versions.get('llama-cpp-python')}, ai2thor {versions.get('ai2thor')}; "
                     f"started {run.manifests[0].get('started')}")
    task_sets = {run.task_ids for run in runs}
    if len(task_sets) > 1:
        parts += ["", "**The runs cover different tasks**: compare their rows with care (each row averages its "
                      "own run's tasks)."]
    parts.append("")
    parts += [table.markdown() for table in tables]
    parts += ["## Figures", "", "![metrics per category](metrics.png)", "", "![time per stage](stages.png)", ""]
    if viewers:
        parts += ["## Viewers", "", "Each run's tasks, with their timelines, maps, stages and plans (open in a "
                  "browser):", ""] + [f"- **{label}**: [{name}]({name})" for label, name in viewers] + [""]
    return "\n".join(parts)


__all__ = ["Run", "Table", "load_run", "markdown", "write_report"]
