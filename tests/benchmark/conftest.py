"""Fixtures for the benchmark tests: the project's task files, loaded once; real benchmark runs."""

from __future__ import annotations

import subprocess
import sys

import pytest

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain


@pytest.fixture(scope="session")
def catalogue():
    return load_domain().catalogue


@pytest.fixture(scope="session")
def all_tasks(catalogue):
    return load_tasks(catalogue=catalogue)


@pytest.fixture(scope="session")
def feasible(all_tasks):
    return [t for t in all_tasks if t.feasible]


@pytest.fixture(scope="session")
def infeasible(all_tasks):
    return [t for t in all_tasks if not t.feasible]


def benchmark_run(out, *args: str, timeout: int = 900) -> subprocess.CompletedProcess:
    """``smartllm-local benchmark run --out OUT ARGS`` in a child process (the real CLI, model and Controller)."""
    proc = subprocess.run([sys.executable, "-m", "smartllm_local", "benchmark", "run", "--out", str(out), *args],
                          capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, proc.stderr
    return proc


#: A task of each category and an infeasible one: where the default suite checks, on a real model, what the
#: heavy suite checks on every task (tests/benchmark/test_whole_benchmark.py).
SAMPLE = ("kitchen-01", "living-02", "kitchen-09", "living-07", "kitchen-inf-02")


@pytest.fixture(scope="session")
def runs(tmp_path_factory):
    """Real runs shared by the method and report tests: the reference plans on every task; Gemma-3 over a task
    of each category and an infeasible one, and without the coalition stage on its complex one (an ablation);
    and decomp-random with SmolLM2 over two seeds."""
    root = tmp_path_factory.mktemp("runs")
    found = {}
    found["reference"] = (root / "ref", benchmark_run(root / "ref", "--method", "reference"))
    sample = [a for t in SAMPLE for a in ("--task", t)]
    found["gemma"] = (root / "gemma", benchmark_run(root / "gemma", "--model", "gemma3-270m", *sample))
    found["ablation"] = (root / "ablation", benchmark_run(root / "ablation", "--model", "gemma3-270m", "--no-coalition",
                                                          "--task", "living-07"))
    seeds = ("--method", "decomp-random", "--seeds", "2", "--task", "kitchen-03", "--task", "kitchen-inf-02")
    found["seeds"] = (root / "random", benchmark_run(root / "random", *seeds))
    found["seeds-again"] = (root / "random", benchmark_run(root / "random", *seeds))
    return found
