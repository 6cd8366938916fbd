"""Locating models: embedded ones through their packages, user paths with clear errors."""

from __future__ import annotations

import subprocess
import sys

import pytest

from smartllm_local.errors import ModelError
from smartllm_local.planner.backends.transformers import _locate
from smartllm_local.planner.models import EMBEDDED, embedded_model_path, is_gguf, resolve_gguf


def test_embedded_models_are_found_through_their_packages():
    for name in EMBEDDED:
        path = embedded_model_path(name)
        assert is_gguf(path) and path.stat().st_size > 50_000_000
    assert resolve_gguf(None) == embedded_model_path("smollm2")


def test_bad_model_paths_say_what_is_wrong(tmp_path):
    with pytest.raises(ModelError, match="does not exist"):
        resolve_gguf(str(tmp_path / "llama-2-70b.gguf"))
    with pytest.raises(ModelError, match="is a folder"):
        resolve_gguf(str(tmp_path))
    text = tmp_path / "notes.gguf"
    text.write_text("not a model")
    with pytest.raises(ModelError, match="not a GGUF"):
        resolve_gguf(str(text))
    with pytest.raises(ModelError, match="no embedded model"):
        embedded_model_path("gpt-4")
    with pytest.raises(ModelError, match="no config.json"):
        _locate(str(tmp_path))


def test_the_cli_rejects_a_missing_model_with_status_2(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "smartllm_local", "plan", "Turn off the light", "--floor-plan", "6",
         "--robots", "1", "--model", str(tmp_path / "missing.gguf")],
        capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 2
    assert "does not exist" in proc.stderr and "Traceback" not in proc.stderr
