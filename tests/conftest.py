"""Shared fixtures: everything here runs against real parts (scene data, ai2thor Controller)."""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

# Scene splits and other derived data go to a per-session folder, never the user's cache.
os.environ.setdefault("SMARTLLM_CACHE_DIR", os.path.join(os.path.dirname(__file__), "..", ".pytest_cache", "smartllm"))
# Where a test names no model it plans with the tiny SmolLM2 (the default model plans, at four times the cost);
# the tests of the default itself clear this.
os.environ["SMARTLLM_MODEL"] = "smollm2"
# ... one candidate and no goal stage before the plan (the CLI's defaults for a model that can plan; the tests of
# candidates and of the goal check name them).
os.environ["SMARTLLM_CANDIDATES"] = "1"
os.environ["SMARTLLM_GOAL_CHECK"] = "false"


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
    processes and of the chat template read."""
    root = tmp_path_factory.mktemp("kitchen-01")
    states, out = root / "states", root / "run"
    proc = subprocess.run([sys.executable, "-m", "smartllm_local", "plan", "--task", "kitchen-01", "--execute",
                           "--prefix-cache", str(states), "--out", str(out)],
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    return Planned(out, states, proc.stdout, proc.stderr)
