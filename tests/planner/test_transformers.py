"""The transformers backend (torch + llguidance) with the real embedded model loaded from its GGUF file."""

from __future__ import annotations

import pytest

from smartllm_local.planner.backends import load_backend
from smartllm_local.planner.backends.base import Sampling
from smartllm_local.planner.grammar import Grammar, alt
from smartllm_local.planner.pipeline import Planner, PlannerConfig
from smartllm_local.robots import load_catalogue


@pytest.fixture(scope="module")
def hf_smollm2():
    backend = load_backend("transformers", "smollm2", n_ctx=4096)
    yield backend
    backend.close()


def test_constraints_bite_through_llguidance(hf_smollm2):
    context = hf_smollm2.tokenize("The capital of France is", bos=True)
    free = hf_smollm2.generate(context, grammar=None, max_tokens=4, sampling=Sampling())
    assert "Paris" in free.text
    grammar = Grammar({"root": alt(" London.\n", " Rome.\n")})
    forced = hf_smollm2.generate(context, grammar=grammar, max_tokens=8, sampling=Sampling())
    assert forced.text in (" London.\n", " Rome.\n")


def test_a_task_planned_through_all_stages(hf_smollm2):
    config = PlannerConfig(budgets={"decomposition": 600, "coalition": 300, "allocation": 700})
    result = Planner(hf_smollm2, load_catalogue(), config).plan("Turn off the light.", 6, [1])
    assert not result.error, result.error
    assert result.plan is not None
    assert result.refusal is not None or [r.stage for r in result.stages] == ["decomposition", "coalition", "allocation"]
