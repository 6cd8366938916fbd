"""The transformers backend (torch + llguidance) with the real embedded model loaded from its GGUF file."""

from __future__ import annotations

import logging
import subprocess
import sys

import pytest
import torch

from smartllm_local.domain import load_domain
from smartllm_local.errors import BackendUnavailableError
from smartllm_local.planner.backends import load_backend
from smartllm_local.planner.backends.transformers import _placement, _quiet_loading
from smartllm_local.planner.decoding.grammar import Grammar, alt
from smartllm_local.planner.decoding.sampling import Sampling
from smartllm_local.planner.models import embedded_model_path
from smartllm_local.planner.pipeline import Planner, PlannerConfig
from smartllm_local.planner.result import PlanResult
from tests.planner.conftest import LOAD_STDERR
from tests.planner.decoding.test_repetition import check_loop_guard


def test_loads_on_the_cpu_in_float32_without_a_progress_bar(hf_smollm2):
    assert hf_smollm2.device.type == "cpu"
    assert hf_smollm2.lm.dtype == torch.float32
    assert "Converting" not in LOAD_STDERR["text"] and "%|" not in LOAD_STDERR["text"]
    assert LOAD_STDERR["text"] == ""


def test_constraints_bite_through_llguidance(hf_smollm2):
    context = hf_smollm2.tokenize("The capital of France is", bos=True)
    free = hf_smollm2.generate(context, grammar=None, max_tokens=4, sampling=Sampling())
    assert "Paris" in free.text
    grammar = Grammar({"root": alt(" London.\n", " Rome.\n")})
    forced = hf_smollm2.generate(context, grammar=grammar, max_tokens=8, sampling=Sampling())
    assert forced.text in (" London.\n", " Rome.\n")


def test_an_end_of_sequence_far_down_the_models_ranking_is_not_its_choice(hf_smollm2):
    """As in the llama.cpp backend: the end of sequence, likelier than anything this grammar admits but not among
    the model's 64 likeliest tokens (at the start of its answer), does not end the line."""
    from smartllm_local.planner.decoding.sampling import may_end
    from smartllm_local.planner.prompting.chat import chat_format, prompt_tokens

    chat, _ = chat_format(hf_smollm2, "auto")
    _, context, _ = prompt_tokens(hf_smollm2, "Answer with one word: is the sky blue?", chat)
    hf_smollm2.sync(context)
    raw = hf_smollm2.next_logits()
    (eos,) = hf_smollm2.end_tokens
    choices = ("qqq\n", "}}}\n")
    starts = [t for t in range(hf_smollm2.n_vocab)
              if (text := hf_smollm2.detokenize([t])) and any(c.startswith(text) for c in choices)]
    assert raw[eos] > raw[starts].max() and not may_end(raw, eos)  # what the case needs
    out = hf_smollm2.generate(context, grammar=Grammar({"root": alt(*choices)}), max_tokens=8, sampling=Sampling())
    assert out.stop == "line" and out.text in choices


def test_a_decomposition_is_a_valid_plan_and_its_prompt_state_is_kept(hf_smollm2):
    """A decomposition through the transformers backend; decomposing again evaluates only what follows the
    scene (the team's skills and the instruction, in its chat turn), and writes what it wrote from an empty
    cache. Every stage is in the heavy suite."""
    planner = Planner(hf_smollm2, load_domain().catalogue, PlannerConfig(budgets={"decomposition": 400}))
    result = PlanResult("Turn off the light.", "FloorPlan6", [1])
    first = planner.decompose(result)
    assert not first.error and (first.refusal is not None or first.plan is not None), first.error
    again = planner.decompose(PlanResult("Turn off the light.", "FloorPlan6", [1]))
    assert again.reused_tokens > again.shared_tokens == first.shared_tokens > 0
    assert again.prompt_tokens - again.reused_tokens < 80
    assert first.reused_tokens == 0 and again.output == first.output


@pytest.mark.heavy
def test_a_task_planned_through_all_stages(hf_smollm2):
    config = PlannerConfig(budgets={"decomposition": 600, "coalition": 300, "allocation": 700})
    planner = Planner(hf_smollm2, load_domain().catalogue, config)
    result = planner.plan("Turn off the light.", 6, [1])
    assert not result.error, result.error
    assert result.plan is not None
    assert result.refusal is not None or list(result.stages) == ["decomposition", "coalition", "allocation"]
    # the examples' and the scene's states are kept in memory: decomposing again evaluates only what follows
    # the scene (the team's skills and the instruction, in its chat turn), and writes what it wrote from an
    # empty cache
    again = planner.decompose(PlanResult("Turn off the light.", "FloorPlan6", [1]))
    assert again.reused_tokens > again.shared_tokens == result.stage("decomposition").shared_tokens > 0
    assert again.prompt_tokens - again.reused_tokens < 80
    decomposition = result.stage("decomposition")
    assert decomposition.reused_tokens == 0 and again.output == decomposition.output


# ------------------------------------------------------------------ loading quietly, failing clearly


def test_the_loop_guard_ends_free_text_that_loops(hf_smollm2):
    check_loop_guard(hf_smollm2)


def test_quiet_loading_hides_progress_bars_but_not_warnings(capfd):
    import transformers
    import transformers.modeling_gguf_pytorch_utils as gguf_utils

    class Keep(logging.Handler):
        def emit(self, record):
            kept.append(record.getMessage())

    kept: list[str] = []
    original, enabled = gguf_utils.tqdm, transformers.utils.logging.is_progress_bar_enabled()
    logger = logging.getLogger("transformers.quantizers.quantizer_gguf")
    handler = Keep()
    logger.addHandler(handler)
    try:
        with _quiet_loading(transformers):
            assert list(gguf_utils.tqdm(range(3), desc="Converting and de-quantizing GGUF tensors...")) == [0, 1, 2]
            logger.warning("Loading a GGUF checkpoint with its weights packed is fastest in float32, and ...")
            logger.warning("a real warning")
    finally:
        logger.removeHandler(handler)
    assert kept == ["a real warning"]
    assert gguf_utils.tqdm is original
    assert transformers.utils.logging.is_progress_bar_enabled() == enabled
    assert "Converting" not in capfd.readouterr().err


def _corrupt_ggufs(folder):
    truncated = folder / "truncated.gguf"
    with open(embedded_model_path("smollm2"), "rb") as handle:
        truncated.write_bytes(handle.read(1 << 20))
    magic_only = folder / "magic-only.gguf"
    magic_only.write_bytes(b"GGUF")
    return [truncated, magic_only]


def _plan_cli(*options):
    return subprocess.run(
        [sys.executable, "-m", "smartllm_local", "plan", "Put the apple in the fridge", "--floor-plan", "6",
         "--robots", "1", "--backend", "transformers", *options],
        capture_output=True, text=True, timeout=300,
    )


def test_the_cli_rejects_corrupt_gguf_files_with_status_2(tmp_path):
    for path in _corrupt_ggufs(tmp_path):
        proc = _plan_cli("--model", str(path))
        assert proc.returncode == 2, proc.stderr
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1, proc.stderr
        assert lines[0].startswith("error: ") and "Traceback" not in proc.stderr
        assert f"{path} is not a readable GGUF file" in lines[0]
        assert "truncated or corrupt" in lines[0]


@pytest.mark.skipif(torch.cuda.is_available(), reason="this machine has CUDA")
def test_gpu_layers_without_cuda_say_how_to_run_on_the_cpu(monkeypatch):
    with pytest.raises(BackendUnavailableError, match=r"has no CUDA support.*--n-gpu-layers 0"):
        load_backend("transformers", "smollm2", n_gpu_layers=-1)
    monkeypatch.setattr(torch.version, "cuda", "12.4")
    with pytest.raises(BackendUnavailableError, match=r"finds no usable GPU.*--n-gpu-layers 0"):
        _placement(torch, 20)
    monkeypatch.undo()
    proc = _plan_cli("--n-gpu-layers", "99")
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr
    assert "--n-gpu-layers 99" in lines[0] and "has no CUDA" in lines[0] and "--n-gpu-layers 0" in lines[0]


def test_gpu_layers_are_all_or_nothing(monkeypatch):
    assert _placement(torch, 0) == (torch.float32, None)
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(torch.cuda, "is_bf16_supported", lambda *a, **k: True)
    assert _placement(torch, -1) == (torch.bfloat16, "cuda")
    assert _placement(torch, 1) == (torch.bfloat16, "cuda")
    monkeypatch.setattr(torch.cuda, "is_bf16_supported", lambda *a, **k: False)
    assert _placement(torch, 99) == (torch.float16, "cuda")


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA GPU")
def test_runs_on_the_gpu_when_asked():
    backend = load_backend("transformers", "smollm2", n_ctx=4096, n_gpu_layers=-1)
    try:
        assert backend.device.type == "cuda"
        assert backend.lm.dtype in (torch.bfloat16, torch.float16)
        context = backend.tokenize("The capital of France is", bos=True)
        assert "Paris" in backend.generate(context, grammar=None, max_tokens=4, sampling=Sampling()).text
        grammar = Grammar({"root": alt(" London.\n", " Rome.\n")})
        for sampling in (Sampling(), Sampling(temperature=0.8, seed=3)):
            forced = backend.generate(context, grammar=grammar, max_tokens=8, sampling=sampling)
            assert forced.text in (" London.\n", " Rome.\n")
        config = PlannerConfig(budgets={"decomposition": 600, "coalition": 300, "allocation": 700})
        result = Planner(backend, load_domain().catalogue, config).plan("Turn off the light.", 6, [1])
        assert not result.error, result.error
    finally:
        backend.close()
