"""Fixtures of the planner's tests: the transformers backend on the embedded SmolLM2, loaded once."""

from __future__ import annotations

import os
import sys
import tempfile

import pytest

#: What loading the transformers backend wrote on file descriptor 2 (tqdm bars, warnings).
LOAD_STDERR: dict[str, str] = {}


def load_capturing_stderr(**kwargs):
    """Load SmolLM2 with the transformers backend, keeping what the load writes on file descriptor 2."""
    from smartllm_local.planner.backends import load_backend

    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile(mode="w+b") as sink:
        os.dup2(sink.fileno(), 2)
        try:
            backend = load_backend("transformers", "smollm2", **kwargs)
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
        sink.seek(0)
        LOAD_STDERR["text"] = sink.read().decode(errors="replace")
    return backend


@pytest.fixture(scope="session")
def hf_smollm2():
    """The embedded SmolLM2 on the transformers backend (torch, llguidance), its GGUF dequantized once."""
    backend = load_capturing_stderr(n_ctx=4096)
    yield backend
    backend.close()
