"""``benchmark report`` over real runs: every number in its tables recomputed here, independently,
from the runs' results lines; the figures are real PNGs; bad input is exit 2."""

from __future__ import annotations

import csv
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

import matplotlib.image
import pytest

from smartllm_local.benchmark.split import load_split
from smartllm_local.benchmark.tasks import SMARTLLM_CATEGORIES as CATEGORIES
from smartllm_local.domain import load_domain
from smartllm_local.report.runs import Run

CLI = [sys.executable, "-m", "smartllm_local", "benchmark", "report"]
METRICS = ("SR", "TCR", "GCR", "RU", "Exe")


def _lines(folder: Path) -> list[dict]:
    return [json.loads(line) for line in (folder / "results.jsonl").read_text().splitlines()]


def _expected_mean(lines: list[dict], category: str | None, metric: str) -> float | None:
    """A category's mean as the paper scores it: an error or a refusal is 0, a metric a task cannot be
    judged on is left out."""
    group = [line for line in lines if line["feasible"] and category in (None, line["category"])]
    values = [line.get(metric, 0.0) for line in group]
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else None


def _rows(path: Path) -> list[dict]:
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def _number(cell: str) -> float | None:
    return None if cell == "" else float(cell)


@pytest.fixture(scope="module")
def report(runs, tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    folders = [runs[name][0] for name in ("reference", "gemma", "ablation", "seeds")]
    proc = subprocess.run([*CLI, *map(str, folders), "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return out, proc


def test_table_one_is_recomputed_from_the_lines_and_the_reference_scores_one_everywhere(runs, report):
    out, proc = report
    rows = _rows(out / "table1.csv")
    test = load_split(load_domain().split_file()).half("test")
    names = ("reference", "gemma", "ablation", "seeds")
    # A run of the household's tasks without --split: its test half's row (where it ran a test-half task), then all.
    parts = [(name, tasks) for name in names
             for tasks in (["test half"] if any(line["feasible"] and line["id"] in test
                                                 for line in _lines(_first(runs[name][0]))) else []) + ["all"]]
    method = {"reference": "reference", "seeds": "decomp-random"}
    assert [(r["Method"], r["Variant"], r["Seeds"], r["Tasks"]) for r in rows] == [
        (method.get(name, "smartllm"), "no coalition" if name == "ablation" else "-", "2" if name == "seeds" else "1",
         tasks) for name, tasks in parts]
    assert parts[0] == ("reference", "test half")
    assert rows[parts.index(("gemma", "all"))]["Model"] == "gemma3-270m-q4_k_m"
    assert rows[parts.index(("seeds", "all"))]["Model"].startswith("SmolLM2-135M")
    for row, (name, tasks) in zip(rows, parts):
        if name == "seeds":
            continue
        lines = [line for line in _lines(runs[name][0])
                 if tasks == "all" or not line["feasible"] or line["id"] in test]
        for category in CATEGORIES:
            for metric in METRICS:
                assert _number(row[f"{category} {metric}"]) == pytest.approx(
                    _expected_mean(lines, category, metric)), (name, tasks, category, metric)
    assert all(float(rows[k][f"{c} {m}"]) == 1.0 for k in (0, 1) for c in CATEGORIES for m in METRICS)
    assert "## Table I: success by task category" in proc.stdout
    assert "**The runs cover different tasks**" in (out / "report.md").read_text()


def _first(folder: Path) -> Path:
    """A run folder, or a --seeds folder's first seed."""
    return folder if (folder / "results.jsonl").is_file() else folder / "seed-0"


def test_a_variant_names_each_switch_set_by_hand():
    def variant(**arguments):
        return Run(Path("run"), [{"identity": {"arguments": arguments}}]).variant

    assert variant() == variant(chat_template="auto") == ""  # the default, whatever it gives a model
    assert variant(chat_template="none", no_token_alignment=True) == "no token alignment, chat template none"
    assert variant(chat_template="on", temperature=0.7) == "chat template on, T=0.7"


def test_the_summary_variant_is_what_a_run_planned_with_whatever_its_model_default():
    def run(planned, **arguments):
        identity = {"arguments": arguments, "settings": {"prompts": {"summary": planned}}}
        return Run(Path("run"), [{"identity": identity}])

    assert run(False, model="qwen2.5-coder-1.5b").ablation == "no summary"  # the model's default: left out
    assert run(True, model="qwen2.5-coder-1.5b", summary=True).variant == ""
    assert run(False, summary=False).variant == "no summary"
    assert Run(Path("old"), [{"identity": {"arguments": {"no_summary": True}}}]).ablation == "no summary"


def test_table_two_gives_the_spread_over_seeds(runs, report):
    out, _ = report
    rows = [r for r in _rows(out / "table2.csv") if r["Tasks"] == "all"]
    assert [(r["Method"], r["Seeds"]) for r in rows] == [("decomp-random", "2")]
    seeds = [_lines(runs["seeds"][0] / f"seed-{s}") for s in (0, 1)]
    for metric in METRICS:
        per_seed = [_expected_mean(lines, "elemental", metric) for lines in seeds]
        assert float(rows[0][f"elemental {metric} mean"]) == pytest.approx(statistics.fmean(per_seed))
        assert float(rows[0][f"elemental {metric} sd"]) == pytest.approx(statistics.stdev(per_seed))
    assert "± " in (out / "report.md").read_text().split("## Table II")[1].split("## Table III")[0]


def test_table_three_sets_each_ablation_beside_the_full_run(runs, report):
    out, _ = report
    rows = _rows(out / "table3.csv")
    assert [(r["Ablation"], r["Method"]) for r in rows] == [("full", "smartllm"), ("no coalition", "smartllm")]
    # like with like: the full run's row is over the ablation run's task
    common = {line["id"] for line in _lines(runs["ablation"][0])}
    assert len(common) == 1 and "Over the 1 task every row's run has" in (out / "report.md").read_text()
    for row, name in zip(rows, ("gemma", "ablation")):
        lines = [line for line in _lines(runs[name][0]) if line["id"] in common]
        for metric in METRICS:
            assert _number(row[metric]) == pytest.approx(_expected_mean(lines, None, metric))
        assert float(row["s/task"]) == pytest.approx(statistics.fmean(line["seconds"] for line in lines))
    assert all(line.get("tokens", {}).get("coalition") is None for line in _lines(runs["ablation"][0]))


def test_refusals_and_stage_costs_are_counted_from_the_lines(runs, report):
    out, _ = report
    refusals = _rows(out / "refusals.csv")
    for row, name in zip(refusals, ("reference", "gemma", "ablation")):
        lines = _lines(runs[name][0])
        infeasible = [line for line in lines if not line["feasible"]]
        assert int(row["Infeasible"]) == len(infeasible)
        assert int(row["Refused"]) == sum(line["refused"] for line in infeasible)
        for who in ("model", "grammar", "rule"):
            assert int(row[f"by {who}"]) == sum(line.get("refused_by") == who for line in infeasible)
        assert int(row["Feasible refused"]) == sum(line["refused"] for line in lines if line["feasible"])
    assert refusals[0]["by rule"] == "7"
    stages = _rows(out / "stages.csv")
    lines = _lines(runs["gemma"][0])
    for stage in ("decomposition", "coalition", "allocation"):
        ran = [line["tokens"][stage] for line in lines if stage in line.get("tokens", {})]
        assert float(stages[1][f"{stage} s"]) == pytest.approx(statistics.fmean(r["seconds"] for r in ran))
        assert float(stages[1][f"{stage} prompt tok"]) == round(statistics.fmean(r["prompt"] for r in ran))
        assert float(stages[1][f"{stage} reused tok"]) == round(statistics.fmean(r["reused"] for r in ran))
    assert float(stages[1]["total h"]) == pytest.approx(sum(line["seconds"] for line in lines) / 3600)


def test_the_figures_are_real_pictures(report):
    out, _ = report
    for name in ("metrics.png", "stages.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        height, width, _ = matplotlib.image.imread(out / name).shape
        assert height > 100 and width > 100


@pytest.mark.parametrize("make, message", [
    (lambda tmp: tmp / "missing", "is not a folder: give the --out folder of a `smartllm-local benchmark run`"),
    (lambda tmp: tmp, "holds no benchmark run (no run.json, no seed-*/run.json)"),
])
def test_a_folder_without_a_run_is_exit_2(tmp_path, make, message):
    proc = subprocess.run([*CLI, str(make(tmp_path)), "--out", str(tmp_path / "r")], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2 and message in proc.stderr
    assert not (tmp_path / "r").exists()


def test_progress_is_plain_lines_in_a_log(runs):
    run, proc = runs["gemma"]
    steps = [line for line in proc.stderr.splitlines() if line.startswith("[")]
    # a step per stage and per execution of each of the 5 tasks (every stage of every task first), then the end
    assert steps[0] == "[0/20] decomposition kitchen-01"
    assert any(line.startswith("[15/20] execution kitchen-01") for line in steps)
    assert steps[-1].startswith("[20/20] done; SR so far ") and steps[-1].endswith("over 4 feasible task(s)")
    # the running SR is the tables' mean: an error or a refusal counts 0
    lines = [json.loads(x) for x in (run / "results.jsonl").read_text().splitlines()]
    sr = sum(line.get("SR") or 0.0 for line in lines if line["feasible"]) / 4
    assert f"SR so far {sr:.2f} over" in steps[-1]


def test_progress_is_a_bar_on_a_terminal(tmp_path, all_tasks):
    """On a terminal (a pseudo-terminal here) stderr shows a rich progress bar, not lines."""
    simple = [t for t in all_tasks if t.category == "simple"]
    steps, feasible = 2 * len(simple), sum(t.feasible for t in simple)  # an allocation and an execution each
    import pty

    command = [sys.executable, "-m", "smartllm_local", "benchmark", "run", "--method", "reference",
               "--category", "simple", "--out", str(tmp_path / "run")]
    leader, follower = pty.openpty()
    proc = subprocess.Popen(command, stdin=follower, stdout=subprocess.PIPE, stderr=follower)
    os.close(follower)
    seen = b""
    while True:
        try:
            chunk = os.read(leader, 4096)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        seen += chunk
    out, _ = proc.communicate(timeout=120)
    os.close(leader)
    text = seen.decode(errors="replace")
    assert proc.returncode == 0
    assert "━" in text and "eta" in text and f"{steps}/{steps}" in text and f"SR 1.00 over {feasible} feasible" in text
    assert f"[{steps}/{steps}]" not in text  # no plain lines on a terminal
    infeasible = len(simple) - feasible
    assert f"correctly refused {infeasible}/{infeasible}".encode() in out
