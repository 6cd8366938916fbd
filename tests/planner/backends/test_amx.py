"""AMX where it runs, plain buffers where it traps: the probe's child, its cached answer, the load without it."""

from __future__ import annotations

import json
import signal
from pathlib import Path

import pytest

from smartllm_local.planner.backends import amx
from smartllm_local.planner.decoding.sampling import Sampling


class Build:
    """What :func:`amx.amx_runs` reads of llama-cpp-python: its system information and version."""

    __version__ = "test"

    def __init__(self, has_amx: bool):
        self.info = b"CPU : AVX2 = 1 | " + (b"AMX_INT8 = 1 | " if has_amx else b"") + b"REPACK = 1 |"

    def llama_print_system_info(self) -> bytes:
        return self.info


def counting(status):
    calls = []

    def run(model_path):
        calls.append(model_path)
        return status
    return run, calls


def test_a_build_without_amx_is_never_probed(tmp_path):
    run, calls = counting(-signal.SIGILL)
    assert amx.amx_runs(Build(has_amx=False), tmp_path / "m.gguf", tmp_path, run) is True
    assert calls == [] and not (tmp_path / amx.CACHE_FILE).exists()


@pytest.mark.parametrize("status, expected", [(-signal.SIGILL, False), (0, True), (1, True)])
def test_the_probes_answer_is_kept_per_model(tmp_path, status, expected):
    """SIGILL alone means AMX traps (a child that fails otherwise leaves the load to fail with its own error)."""
    model = tmp_path / "m.gguf"
    model.write_bytes(b"weights")
    run, calls = counting(status)
    assert amx.amx_runs(Build(has_amx=True), model, tmp_path, run) is expected
    assert amx.amx_runs(Build(has_amx=True), model, tmp_path, run) is expected
    assert len(calls) == 1
    assert list(json.loads((tmp_path / amx.CACHE_FILE).read_text()).values()) == [expected]
    other = tmp_path / "other.gguf"
    other.write_bytes(b"other weights")
    amx.amx_runs(Build(has_amx=True), other, tmp_path, run)
    assert len(calls) == 2  # another model file: AMX kernels exist for some weight types only


def test_a_cache_that_cannot_be_written_costs_only_a_probe_per_process(tmp_path):
    model = tmp_path / "m.gguf"
    model.write_bytes(b"weights")
    run, calls = counting(-signal.SIGILL)
    (tmp_path / "file").write_text("x")
    for unwritable in (tmp_path / "file" / "cache", tmp_path / "cache"):  # under a file; its map a folder
        (tmp_path / "cache" / amx.CACHE_FILE).mkdir(parents=True, exist_ok=True)
        assert amx.amx_runs(Build(has_amx=True), model, unwritable, run) is False
        assert amx.amx_runs(Build(has_amx=True), model, unwritable, run) is False
    assert calls == [model] * 4


def test_a_probe_that_does_not_end_is_not_kept_and_a_missing_model_is_not_probed(tmp_path):
    run, calls = counting(None)
    model = tmp_path / "m.gguf"
    assert amx.amx_runs(Build(has_amx=True), model, tmp_path, run) is True
    assert calls == []  # no file: the load itself says so
    model.write_bytes(b"weights")
    assert amx.amx_runs(Build(has_amx=True), model, tmp_path, run) is True
    assert calls == [model] and not (tmp_path / amx.CACHE_FILE).exists()


def test_the_probe_reports_a_child_killed_by_sigill(tmp_path):
    """The real child process: one that dies of SIGILL as a trapped AMX instruction kills it, and one that ends."""
    died = "import os, signal, sys; assert sys.argv[1].endswith('m.gguf'); os.kill(os.getpid(), signal.SIGILL)"
    assert amx.probe(tmp_path / "m.gguf", code=died) == -signal.SIGILL
    assert amx.probe(tmp_path / "m.gguf", code="pass") == 0


def test_the_real_probe_loads_the_model_and_its_answer_is_used(tmp_path, smollm2):
    """On this machine's llama.cpp: the probe's child loads SmolLM2 and evaluates tokens; where AMX is built in,
    its answer decides the load, and the loaded backend (which decodes, as every other test shows) says so."""
    import llama_cpp

    from smartllm_local.planner.backends import load_backend

    model = Path(smollm2.model)
    status = amx.probe(model)
    assert status in (0, -signal.SIGILL)
    runs = amx.amx_runs(llama_cpp, model, tmp_path)
    assert runs is (status == 0 or not amx.amx_in_build(llama_cpp))
    assert ("extra_buffers" in smollm2._settings) is not amx.amx_runs(llama_cpp, model)
    backend = load_backend("llamacpp", str(model), n_ctx=256)
    try:
        context = backend.tokenize("1, 2, 3,", bos=True)
        assert backend.generate(context, grammar=None, max_tokens=2, sampling=Sampling()).text
    finally:
        backend.close()


def test_plain_buffers_are_asked_for_while_the_model_loads_only():
    import llama_cpp

    before = llama_cpp.llama_cpp.llama_model_default_params().use_extra_bufts
    with amx.without_extra_buffers(llama_cpp, wanted=True):
        assert llama_cpp.llama_cpp.llama_model_default_params().use_extra_bufts is False
    assert llama_cpp.llama_cpp.llama_model_default_params().use_extra_bufts == before
    with amx.without_extra_buffers(llama_cpp, wanted=False):
        assert llama_cpp.llama_cpp.llama_model_default_params().use_extra_bufts == before
