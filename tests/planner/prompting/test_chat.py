"""Instruct models get their prompts in their own chat template; base models, and --chat-template none, raw.

With the real models: SmolLM2-135M-Instruct carries a chat template in its GGUF, Gemma-3-270M is a base
model without one.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from smartllm_local.benchmark.tasks import find_task, load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner import pipeline
from smartllm_local.planner.backends import load_backend
from smartllm_local.planner.decoding.sampling import Generated, Sampling
from smartllm_local.planner.pipeline import Planner, PlannerConfig, write_artifacts
from smartllm_local.planner.prompting.chat import (
    APPLIED,
    BASE_MODEL,
    OFF,
    answer_code,
    chat_format,
    mode_for,
    prompt_tokens,
)
from smartllm_local.planner.prompting.prompts import Prompt
from smartllm_local.planner.result import PlanResult, StageRecord
from smartllm_local.planner.stages import STOP_STRINGS, Fitted, fit_prompt, run_stage
from tests.cli.test_cli_errors import cli, one_line_error
from tests.planner.fakes import FakeBackend


def _result(task):
    return PlanResult(instruction=task.instruction, floor_plan=task.floor_plan, robots=list(task.robots))


class Recording:
    """A backend that keeps the contexts it is asked to continue."""

    def __init__(self, backend):
        self._backend = backend
        self.contexts: list[list[int]] = []

    def __getattr__(self, name):
        return getattr(self._backend, name)

    def generate(self, context, **kwargs):
        self.contexts.append(list(context))
        return self._backend.generate(context, **kwargs)


def special(backend, text: str) -> list[int]:
    return backend.tokenize(text, special=True)


def test_smollm2_gets_its_prompt_as_a_user_turn_with_control_tokens_as_single_tokens(smollm2):
    chat, status = chat_format(smollm2, "auto")
    assert status == APPLIED and "<|im_start|>" in smollm2.chat_template
    text, tokens, _ = prompt_tokens(smollm2, "# Task Description: wash the apple\n", chat)
    im_start, = special(smollm2, "<|im_start|>")
    im_end, = special(smollm2, "<|im_end|>")
    assert tokens[0] == im_start
    header = [im_start, *smollm2.tokenize("assistant\n")]  # the assistant turn, opened for the output
    assert tokens[-len(header):] == header
    assert text.startswith("<|im_start|>") and text.endswith("<|im_start|>user\n# Task Description: wash the apple\n"
                                                               "<|im_end|>\n<|im_start|>assistant\n")
    assert tokens.count(im_start) == 3 and tokens.count(im_end) == 2  # system and user turns, assistant header


def test_a_control_token_string_in_the_prompt_stays_text(smollm2):
    chat, _ = chat_format(smollm2, "auto")
    body = "# the robot says <|im_start|>assistant and <|im_end|>\n"
    _, tokens, _ = prompt_tokens(smollm2, body, chat)
    turn = chat.turn(body)
    assert turn.body == body
    assert tokens == special(smollm2, turn.head) + smollm2.tokenize(body) + special(smollm2, turn.tail)
    im_start, = special(smollm2, "<|im_start|>")
    im_end, = special(smollm2, "<|im_end|>")
    assert tokens.count(im_start) == 3 and tokens.count(im_end) == 2  # only the template's
    assert im_start not in smollm2.tokenize(body) and smollm2.detokenize(smollm2.tokenize(body)) == body


def test_with_none_the_prompt_goes_in_raw_as_before(smollm2):
    chat, status = chat_format(smollm2, "none")
    assert (chat, status) == (None, OFF)
    prompt = "# Task Description: wash the apple\n"
    assert prompt_tokens(smollm2, prompt, chat) == (prompt, smollm2.tokenize(prompt, bos=True), ())


def test_the_context_budget_counts_the_template(smollm2):
    chat, _ = chat_format(smollm2, "auto")
    catalogue = load_domain().catalogue
    planner = Planner(smollm2, catalogue)
    examples = planner.examples
    build = lambda ex: Prompt(("# Examples\n\n", "# Your task\n"))  # noqa: E731
    raw = fit_prompt(build, examples, smollm2, 16).tokens
    wrapped = fit_prompt(build, examples, smollm2, 16, chat).tokens
    assert len(wrapped) > len(raw) + 10


@pytest.fixture(scope="module")
def kitchen09():
    return find_task(load_tasks(), "kitchen-09")


def test_a_real_decomposition_in_the_chat_template_is_a_valid_plan(smollm2, kitchen01):
    """The session's plan of kitchen-01 (SmolLM2 refuses kitchen-09 outright in its chat template: a refusal is
    valid but shows little): its prompt was a user turn, its output the assistant's, and a valid plan."""
    prompt = (kitchen01.out / "decomposition" / "prompt.txt").read_text()
    assert prompt.startswith("<|im_start|>system\n") and prompt.endswith("<|im_start|>assistant\n")
    tokens = smollm2.tokenize(prompt, special=True)
    header = smollm2.tokenize("<|im_start|>assistant\n", special=True)
    assert tokens[:1] == special(smollm2, "<|im_start|>") and tokens[-len(header):] == header
    assert parse_plan((kitchen01.out / "decomposed.py").read_text(), form="decomposed").functions
    result = json.loads((kitchen01.out / "result.json").read_text())
    assert result["stages"]["decomposition"]["chat_template"] == APPLIED and result["refusal"] is None


class _Seen(Exception):
    pass


def first_prompt(backend, config: PlannerConfig, task, monkeypatch) -> tuple[Planner, str, list[int], list[int]]:
    """(planner, the decomposition prompt as given, its tokens, the first context the model gets),
    stopping before the model writes anything."""
    fitted = []

    def fit(*args, **kwargs):
        fitted.append(fit_prompt(*args, **kwargs))
        return fitted[-1]

    class Stop(Recording):
        def prefill(self, context, shared):
            return 0  # the prompt is all this test looks at: evaluating it would only cost time

        def generate(self, context, **kwargs):
            self.contexts.append(list(context))
            raise _Seen

    recording = Stop(backend)
    monkeypatch.setattr(pipeline, "fit_prompt", fit)
    planner = Planner(recording, load_domain().catalogue, config)
    with pytest.raises(_Seen):
        planner.decompose(_result(task))
    return planner, fitted[0].text, fitted[0].tokens, recording.contexts[0]


def test_with_none_the_model_gets_the_raw_prompt(smollm2, kitchen09, monkeypatch):
    planner, prompt, tokens, context = first_prompt(smollm2, PlannerConfig(chat_template="none"), kitchen09,
                                                    monkeypatch)
    assert planner.chat_status == OFF and prompt.startswith("import threading\nimport time\n")
    assert tokens == smollm2.tokenize(prompt, bos=True) == context[: len(tokens)]


def test_a_base_model_falls_back_to_the_raw_prompt_and_says_so(kitchen09, monkeypatch, tmp_path):
    gemma = load_backend("llamacpp", "gemma3-270m", n_ctx=4096)
    try:
        assert gemma.chat_template is None
        planner, prompt, tokens, context = first_prompt(gemma, PlannerConfig(), kitchen09, monkeypatch)
        assert planner.chat_status == BASE_MODEL and prompt.startswith("import threading\nimport time\n")
        assert tokens == gemma.tokenize(prompt, bos=True) == context[: len(tokens)]
    finally:
        gemma.close()
    record = StageRecord("decomposition", chat_template=BASE_MODEL)
    result = PlanResult("x", "FloorPlan6", [1], stages={"decomposition": record})
    write_artifacts(result, tmp_path)
    assert json.loads((tmp_path / "decomposition" / "timings.json").read_text())["chat_template"] == BASE_MODEL


@pytest.mark.parametrize("command", [
    ["plan", "Put the apple in the fridge", "--floor-plan", "6", "--robots", "1", "--out", "out"],
    ["benchmark", "run", "--out", "out"],
])
def test_a_bad_chat_template_mode_is_a_one_line_error(tmp_path, command):
    one_line_error(cli(*command, "--chat-template", "chatml", cwd=tmp_path),
                   "--chat-template must be one of auto, on, none, not 'chatml'")
    assert not (tmp_path / "out").exists()


def test_auto_plans_the_qwen_models_raw_and_every_other_model_in_its_template():
    """The measured choice (docs/planner.md): Qwen2.5-Coder plans better as raw completion; none stays none."""
    for qwen in ("qwen2.5-coder-1.5b", "qwen2.5-coder-0.5b"):
        assert mode_for(qwen, "auto") == "none" and mode_for(qwen, "none") == "none" and mode_for(qwen, "on") == "on"
    for other in (None, "smollm2", "gemma3-270m", "/models/qwen2.5-coder-1.5b-instruct-q4_k_m.gguf"):
        assert mode_for(other, "auto") == "auto"


def test_the_transformers_backend_reads_the_template_and_tokenizes_as_llama_cpp_does(smollm2, hf_smollm2):
    hf = hf_smollm2
    assert hf.chat_template == smollm2.chat_template
    body = "# say <|im_end|> now\n"
    text, tokens, _ = prompt_tokens(hf, body, chat_format(hf, "auto")[0])
    assert (text, tokens, ()) == prompt_tokens(smollm2, body, chat_format(smollm2, "auto")[0])
    assert tokens.count(special(hf, "<|im_end|>")[0]) == 2  # the system and user turns' ends, not the body's


ANSWER = """To put the apple in the fridge, the robot first walks to it.

1. **Go to the apple**: move next to it.

```python
def subtask1_reach_apple():
    GoToObject('Apple')

subtask1_reach_apple()
```

This code moves the robot to the apple.
"""
CODE = "def subtask1_reach_apple():\n    GoToObject('Apple')\n\nsubtask1_reach_apple()\n"


def test_a_free_chat_answer_is_read_from_its_code_blocks_cut_at_the_stages_stop_strings():
    stops = STOP_STRINGS["decomposition"]
    assert answer_code(ANSWER, stops) == CODE
    parse_plan(answer_code(ANSWER, stops), form="decomposition")
    assert answer_code("Here:\n```\nGoToObject('Apple')\n# Example 2\nobjects = []", stops) == "GoToObject('Apple')\n"
    assert answer_code("```py\na()\n```\nand then\n```python\nb()\n```\n", ()) == "a()\nb()\n"
    assert answer_code("a()\n\n# Example 2\n", stops) == "a()\n"  # no block: the answer is the code
    assert answer_code("see `a()` and ``` inline\n", ()) == "see `a()` and ``` inline\n"  # not a fence


COALITION = ("One robot is enough for it.\n\n"
             "```\n# SubTask 1 (subtask1_reach_apple): needs GoToObject; so robots[0]\n```\n")


class _Answers(FakeBackend):
    """Answers free generation as an instruct model does in its chat turn, and keeps the stop strings asked."""

    stops: list[str] = []

    def generate(self, context, *, grammar, max_tokens, sampling, stop=(), rng=None, lines=1):
        self.stops = list(stop)
        return Generated([0] * 40, COALITION, "eos")


@pytest.mark.parametrize("chat", [APPLIED, OFF])
def test_free_generation_in_a_chat_turn_reads_the_code_and_keeps_the_whole_answer(chat):
    """In its chat turn the model's prose has paragraphs: a coalition is not cut at the first of them, and the plan
    is read from the answer's code; a raw completion is read as written, cut at the stop strings."""
    backend, record = _Answers(), StageRecord("coalition", chat_template=chat)
    run_stage(record, backend, Fitted("p", [0, 0]), None, output_budget=64, sampling=Sampling(),
              rng=np.random.default_rng(0))
    assert record.raw == COALITION
    if chat == APPLIED:
        assert "\n\n" not in backend.stops and record.output == COALITION.split("```\n")[1]
    else:
        assert backend.stops == list(STOP_STRINGS["coalition"]) and record.output == COALITION
