"""Locating models: embedded ones through their packages, user paths with clear errors."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from smartllm_local.cli.options import ModelOptions
from smartllm_local.errors import ModelError
from smartllm_local.planner.backends.transformers import _locate
from smartllm_local.planner.models import EMBEDDED, SplitOverPackages, embedded_model_path, is_gguf, resolve_gguf


def test_embedded_models_are_found_through_their_packages():
    for name in EMBEDDED:
        path = embedded_model_path(name)
        assert is_gguf(path) and path.stat().st_size > 50_000_000


def test_the_default_model_is_qwen_1_5b_unless_smartllm_model_names_another(monkeypatch):
    monkeypatch.delenv("SMARTLLM_MODEL")
    assert resolve_gguf(None) == embedded_model_path("qwen2.5-coder-1.5b")
    assert ModelOptions().config.chat_template == "none", "the default model plans raw, as measured"
    monkeypatch.setenv("SMARTLLM_MODEL", "smollm2")
    assert resolve_gguf(None) == embedded_model_path("smollm2")
    assert ModelOptions().config.chat_template == "auto"


def test_decompositions_start_with_the_summary_but_for_the_models_measured_better_without(monkeypatch):
    monkeypatch.delenv("SMARTLLM_MODEL", raising=False)
    assert not ModelOptions().config.prompts.summary, "the default model (1.5B) goes without the summary"
    assert not ModelOptions(model="qwen2.5-coder-0.5b").config.prompts.summary
    assert ModelOptions(model="smollm2").config.prompts.summary
    assert ModelOptions(model="qwen2.5-coder-1.5b", summary=True).config.prompts.summary
    assert not ModelOptions(model="smollm2", summary=False).config.prompts.summary
    assert ModelOptions(backend="server", endpoint="http://127.0.0.1:1").config.prompts.summary


def test_the_qwen_models_are_instruct_models_with_their_template_and_32k_context():
    from smartllm_local.planner.backends.llamacpp import LlamaCppBackend

    for name, blocks in (("qwen2.5-coder-0.5b", "24"), ("qwen2.5-coder-1.5b", "28")):
        vocab = LlamaCppBackend(embedded_model_path(name), n_ctx=512, vocab_only=True)
        try:
            assert vocab.trained_context == 32768 and "<|im_start|>" in vocab.chat_template
            assert vocab.llm.metadata["qwen2.block_count"] == blocks and vocab.eos_token == "<|im_end|>"
        finally:
            vocab.close()


def _parts(folder, module: str, chunks: list[bytes]) -> None:
    """Packages ``module{n}`` holding ``data/partNN.bin``, as the Qwen uploads are laid out."""
    for n, chunk in enumerate(chunks, 1):
        data = folder / f"{module}{n}" / "data"
        data.mkdir(parents=True)
        (data.parent / "__init__.py").write_text("")
        (data / f"part{n:02d}.bin").write_bytes(chunk)


def test_a_model_split_over_packages_is_assembled_once_and_trusted_only_by_its_digest(tmp_path, monkeypatch):
    import hashlib

    chunks = [b"GGUF" + bytes(range(256)) * 40, b"second part", b"and the last"]
    _parts(tmp_path / "site", "fake_split_part", chunks)
    monkeypatch.syspath_prepend(str(tmp_path / "site"))
    whole = b"".join(chunks)
    good = SplitOverPackages("fake_split_part{n}", 3, "fake.gguf", len(whole), hashlib.sha256(whole).hexdigest(),
                             "fake-split")
    cache = tmp_path / "cache"
    path = good.path(cache)
    assert path.read_bytes() == whole and path == cache / "models" / "fake.gguf"
    mtime = path.stat().st_mtime_ns
    assert good.path(cache) == path and path.stat().st_mtime_ns == mtime  # assembled once
    path.write_bytes(whole[:-1] + b"!")  # the cached file changed under it: refused, never trusted
    with pytest.raises(ModelError, match="is not the pinned fake.gguf"):
        good.path(cache)
    wrong = SplitOverPackages("fake_split_part{n}", 3, "other.gguf", len(whole), "0" * 64, "fake-split")
    with pytest.raises(ModelError, match="do not make the pinned file.*reinstall"):
        wrong.path(cache)
    assert sorted(p.name for p in (cache / "models").iterdir()) == ["fake.gguf"]  # nothing half-written left
    missing = SplitOverPackages("fake_split_part{n}", 4, "more.gguf", 1, "0" * 64, "smartllm-local[fake]")
    with pytest.raises(ModelError, match=r"fake_split_part4 is not installed: pip install 'smartllm-local\[fake\]'"):
        missing.path(cache)


def test_a_qwen_file_that_is_not_the_pinned_one_is_exit_2_and_never_loaded(tmp_path):
    spec = EMBEDDED["qwen2.5-coder-0.5b"]
    cache = tmp_path / "cache"
    (cache / "models").mkdir(parents=True)
    with open(cache / "models" / spec.filename, "wb") as forged:  # the right size, other bytes
        forged.write(b"GGUF")
        forged.truncate(spec.size)
    proc = subprocess.run(
        [sys.executable, "-m", "smartllm_local", "plan", "Turn off the light", "--floor-plan", "6", "--robots", "1",
         "--model", "qwen2.5-coder-0.5b"], capture_output=True, text=True, timeout=120,
        env={**os.environ, "SMARTLLM_CACHE_DIR": str(cache)})
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.startswith("error: ") and "is not the pinned" in proc.stderr and "not loaded" in proc.stderr


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
