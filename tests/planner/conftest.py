"""Real models for the planner tests: the embedded SmolLM2 GGUF, loaded once per session."""

from __future__ import annotations

import pytest

from smartllm_local.planner.backends import load_backend


@pytest.fixture(scope="session")
def smollm2():
    backend = load_backend("llamacpp", "smollm2", n_ctx=4096)
    yield backend
    backend.close()
