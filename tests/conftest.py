"""Shared fixtures: everything here runs against real parts (scene data, ai2thor Controller, the models): the
project's task files, loaded once, and real benchmark runs the benchmark's and the report's tests read."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from filelock import FileLock

# Scene splits and other derived data go to a per-session folder, never the user's cache.
os.environ.setdefault("SMARTLLM_CACHE_DIR", os.path.join(os.path.dirname(__file__), "..", ".pytest_cache", "smartllm"))
# Where a test names no model it plans with the tiny SmolLM2 (the default model plans, at four times the cost);
# the tests of the default itself clear this.
os.environ["SMARTLLM_MODEL"] = "smollm2"
# ... one candidate and no goal stage before the plan (the CLI's defaults for a model that can plan; the tests of
# candidates and of the goal check name them).
os.environ["SMARTLLM_CANDIDATES"] = "1"
os.environ["SMARTLLM_GOAL_CHECK"] = "false"


#: The files whose tests read the ``runs`` fixture (five minutes of benchmark runs): the suite runs on two
#: workers (pytest-xdist), each file's tests on one, and these files on the one that makes the runs.
RUNS_FILES = ("tests/benchmark/test_methods.py", "tests/report/test_report.py", "tests/report/viewer/test_viewer.py")


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log):
    """pytest-xdist's ``loadfile`` distribution, with the files of :data:`RUNS_FILES` as one file (unless another
    ``--dist`` is asked for)."""
    from xdist.scheduler import LoadFileScheduling

    if config.getvalue("dist") != "load":
        return None

    class SharedRuns(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            scope = super()._split_scope(nodeid)
            return RUNS_FILES[0] if scope in RUNS_FILES else scope

    return SharedRuns(config, log)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """A test that reads ``runs`` outside :data:`RUNS_FILES` would make the runs again on another worker."""
    strays = {item.nodeid.split("::")[0] for item in items if "runs" in getattr(item, "fixturenames", ())}
    if strays - set(RUNS_FILES):
        raise pytest.UsageError(f"add {sorted(strays - set(RUNS_FILES))} to RUNS_FILES in tests/conftest.py")


@pytest.fixture(scope="session")
def fp6_controller():
    """A stand-in Controller on FloorPlan6 with 3 agents, shared by read-mostly tests (reset before use)."""
    from smartllm_local.world.controller import open_controller

    controller = open_controller(6, agent_count=3)
    yield controller
    controller.stop()


@pytest.fixture(scope="session")
def smollm2():
    """The embedded SmolLM2 GGUF on llama.cpp, loaded once per session."""
    from smartllm_local.planner.backends import load_backend

    backend = load_backend("llamacpp", "smollm2", n_ctx=8192)
    yield backend
    backend.close()


@dataclass(frozen=True)
class Planned:
    out: Path  # the plan command's --out folder
    states: Path  # its prefix store, empty before it ran
    stdout: str
    stderr: str  # not a terminal: a line per stage


@pytest.fixture(scope="session")
def kitchen01(tmp_path_factory) -> Planned:
    """SmolLM2 plans and executes kitchen-01 through the CLI (``plan --task kitchen-01 --execute --out``), with a
    prefix store of its own: the one such run, which the tests of its artifacts, of the prefix store across
    processes and of the chat template read. Made once for the session's workers: the first to need it makes
    it in the folder they share (pytest-xdist's way, under a file lock), the others wait and read it."""
    shared = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        shared = shared.parent  # the workers' basetemps are folders of one session's
    root = shared / "kitchen-01"
    states, out, made = root / "states", root / "run", root / "made.json"
    with FileLock(f"{root}.lock"):
        if not made.is_file():
            root.mkdir(exist_ok=True)
            proc = subprocess.run([sys.executable, "-m", "smartllm_local", "plan", "--task", "kitchen-01", "--execute",
                                   "--prefix-cache", str(states), "--out", str(out)],
                                  capture_output=True, text=True, timeout=900)
            assert proc.returncode == 0, proc.stderr
            made.write_text(json.dumps({"stdout": proc.stdout, "stderr": proc.stderr}))
    streams = json.loads(made.read_text())
    return Planned(out, states, streams["stdout"], streams["stderr"])


@pytest.fixture(scope="session")
def catalogue():
    from smartllm_local.domain import load_domain

    return load_domain().catalogue


@pytest.fixture(scope="session")
def all_tasks(catalogue):
    from smartllm_local.benchmark.tasks import load_tasks

    return load_tasks(catalogue=catalogue)


def benchmark_run(out, *args: str, timeout: int = 900) -> subprocess.CompletedProcess:
    """``smartllm-local benchmark run --out OUT ARGS`` in a child process (the real CLI, model and Controller)."""
    proc = subprocess.run([sys.executable, "-m", "smartllm_local", "benchmark", "run", "--out", str(out), *args],
                          capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, proc.stderr
    return proc


#: A task of each category and an infeasible one: where the default suite checks, on a real model, what the
#: heavy suite checks on every task (tests/benchmark/test_whole_benchmark.py).
#: The household's task sets: the benchmark's, then those beside it (folders of the domain).
HOUSEHOLD_SETS = ("benchmark", "heldout", "development", "development-3", "development-4", "development-5",
                  "development-6", "development-7", "development-8", "development-9", "development-10",
                  "development-11", "development-12", "development-13", "development-14", "development-15")
SAMPLE = ("kitchen-01", "living-02", "kitchen-09", "living-07", "kitchen-inf-02")


@pytest.fixture(scope="session")
def runs(tmp_path_factory):
    """Real runs shared by the method and report tests: the reference plans on every task; Gemma-3 over a task
    of each category and an infeasible one, and without the coalition stage on its complex one (an ablation);
    and decomp-random with SmolLM2 over two seeds (one task: Table II's spread needs seeds, not tasks)."""
    root = tmp_path_factory.mktemp("runs")
    found = {}
    found["reference"] = (root / "ref", benchmark_run(root / "ref", "--method", "reference"))
    sample = [a for t in SAMPLE for a in ("--task", t)]
    found["gemma"] = (root / "gemma", benchmark_run(root / "gemma", "--model", "gemma3-270m", *sample))
    found["ablation"] = (root / "ablation", benchmark_run(root / "ablation", "--model", "gemma3-270m", "--no-coalition",
                                                          "--task", "living-07"))
    seeds = ("--method", "decomp-random", "--seeds", "2", "--task", "kitchen-03")
    found["seeds"] = (root / "random", benchmark_run(root / "random", *seeds))
    found["seeds-again"] = (root / "random", benchmark_run(root / "random", *seeds))
    return found
