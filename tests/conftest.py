"""Shared fixtures: everything here runs against real parts (scene data, ai2thor Controller)."""

from __future__ import annotations

import os

import pytest

# Scene splits and other derived data go to a per-session folder, never the user's cache.
os.environ.setdefault("SMARTLLM_CACHE_DIR", os.path.join(os.path.dirname(__file__), "..", ".pytest_cache", "smartllm"))


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
