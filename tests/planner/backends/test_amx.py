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


def counting(status, plain=0):
    """A probe that answers ``status`` with llama.cpp's extra buffers and ``plain`` without, and its calls."""
    calls = []

    def run(model_path, without):
        calls.append((model_path, without))
        return plain if without else status
    return run, calls


def test_a_build_without_amx_is_never_probed(tmp_path):
    run, calls = counting(-signal.SIGILL)
    assert amx.amx_runs(Build(has_amx=False), tmp_path / "m.gguf", tmp_path, run) is True
    assert calls == [] and not (tmp_path / amx.CACHE_FILE).exists()


@pytest.mark.parametrize("status, plain, expected, probes", [
    (-signal.SIGILL, 0, False, 2), (-signal.SIGSEGV, 0, False, 2),  # the trap as two guests showed it
    (-signal.SIGSEGV, -signal.SIGSEGV, True, 2), (-signal.SIGILL, 1, True, 2),  # dies without AMX too: not AMX's
    (0, 0, True, 1), (1, 0, True, 1)])  # a child that fails otherwise leaves the load to fail with its own error
def test_the_probes_answer_is_kept_per_model(tmp_path, status, plain, expected, probes):
    """AMX traps where the child dies of a signal with llama.cpp's extra buffers and ends well without them."""
    model = tmp_path / "m.gguf"
    model.write_bytes(b"weights")
    run, calls = counting(status, plain)
    assert amx.amx_runs(Build(has_amx=True), model, tmp_path, run) is expected
    assert amx.amx_runs(Build(has_amx=True), model, tmp_path, run) is expected
    assert calls == [(model, False), (model, True)][:probes]
    assert list(json.loads((tmp_path / amx.CACHE_FILE).read_text()).values()) == [expected]
    other = tmp_path / "other.gguf"
    other.write_bytes(b"other weights")
    amx.amx_runs(Build(has_amx=True), other, tmp_path, run)
    assert len(calls) == 2 * probes  # another model file: AMX kernels exist for some weight types only


def test_a_cache_that_cannot_be_written_costs_only_a_probe_per_process(tmp_path):
    model = tmp_path / "m.gguf"
    model.write_bytes(b"weights")
    run, calls = counting(-signal.SIGILL)
    (tmp_path / "file").write_text("x")
    for unwritable in (tmp_path / "file" / "cache", tmp_path / "cache"):  # under a file; its map a folder
        (tmp_path / "cache" / amx.CACHE_FILE).mkdir(parents=True, exist_ok=True)
        assert amx.amx_runs(Build(has_amx=True), model, unwritable, run) is False
        assert amx.amx_runs(Build(has_amx=True), model, unwritable, run) is False
    assert calls == [(model, False), (model, True)] * 4


@pytest.mark.parametrize("status, plain", [(None, 0), (-signal.SIGSEGV, None)])
def test_a_probe_that_does_not_end_is_not_kept_and_a_missing_model_is_not_probed(tmp_path, status, plain):
    run, calls = counting(status, plain)
    model = tmp_path / "m.gguf"
    assert amx.amx_runs(Build(has_amx=True), model, tmp_path, run) is True
    assert calls == []  # no file: the load itself says so
    model.write_bytes(b"weights")
    assert amx.amx_runs(Build(has_amx=True), model, tmp_path, run) is True
    assert calls == [(model, False), (model, True)][:1 if status is None else 2]
    assert not (tmp_path / amx.CACHE_FILE).exists()


def test_the_probe_reports_a_child_killed_by_a_signal(tmp_path):
    """The real child process: one that dies of SIGILL as a trapped AMX instruction kills it unless told "plain",
    and one that ends."""
    died = ("import os, signal, sys; assert sys.argv[1].endswith('m.gguf')\n"
            "if sys.argv[2:] != ['plain']: os.kill(os.getpid(), signal.SIGILL)")
    assert amx.probe(tmp_path / "m.gguf", code=died) == -signal.SIGILL
    assert amx.probe(tmp_path / "m.gguf", plain=True, code=died) == 0
    assert amx.probe(tmp_path / "m.gguf", code="pass") == 0


def test_the_real_probe_loads_the_model_and_its_answer_is_used(tmp_path, smollm2):
    """On this machine's llama.cpp: the probe's child loads SmolLM2 and evaluates tokens; where AMX is built in,
    its answer decides the load, and the loaded backend (which decodes, as every other test shows) says so."""
    import llama_cpp

    from smartllm_local.planner.backends import load_backend

    model = Path(smollm2.model)
    status = amx.probe(model)
    assert status in (0, -signal.SIGILL, -signal.SIGSEGV)
    assert amx.probe(model, plain=True) == 0
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
