"""Server dialects without a server: how each is recognized, what a request carries, what an answer says.

The answers are ones a real vLLM gave (0.32.0 on the CPU, SmolLM2); the servers themselves are driven
in test_server_backend.py and test_vllm.py.
"""

from __future__ import annotations

import pytest

from smartllm_local.errors import UserError
from smartllm_local.planner.backends.server.dialects import LlamaCppPythonServer, LlamaServer, Vllm, probe


def _vllm_answer(text: str, token_ids: list[int], finish: str, stop_reason, cached: int | None = 0,
                 prompt: int = 28) -> dict:
    details = None if cached is None else {"cached_tokens": cached, "created_cache_tokens": None,
                                           "multimodal_tokens": None}
    return {"object": "text_completion", "model": "/models/smollm2",
            "choices": [{"index": 0, "text": text, "finish_reason": finish, "stop_reason": stop_reason,
                         "token_ids": token_ids, "prompt_token_ids": [1, 4093, 198]}],
            "usage": {"prompt_tokens": prompt, "completion_tokens": len(token_ids), "prompt_tokens_details": details}}


def test_vllm_leaves_out_the_end_of_sequence_it_lists_with_what_it_wrote():
    # vLLM ends a line its grammar completed with the end-of-sequence token (2, <|im_end|>), listed, not written
    reply = Vllm().reply(_vllm_answer("I like apples\n", [57, 702, 253, 96, 439, 266, 198, 2], "stop", None, 0, 13))
    assert reply.tokens == [57, 702, 253, 96, 439, 266, 198] and reply.finish == "eos" and reply.evaluated == 13
    # a 4,600-token prompt asked for again: all but its last 24 tokens (not a whole block) from the prefix cache
    again = Vllm().reply(_vllm_answer("The", [504], "length", None, 4576, 4600))
    assert again.evaluated == 24
    # a stop token (here asked for: 198, a newline) is listed too, its id the stop reason
    ended = Vllm().reply(_vllm_answer("The Unreliable Assassin: A Tale of Two Cities",
                                      [504, 810, 257, 26667, 2439, 520, 254, 42, 330, 30379, 282, 5713, 20281, 198],
                                      "stop", 198))
    assert ended.tokens == [504, 810, 257, 26667, 2439, 520, 254, 42, 330, 30379, 282, 5713, 20281]
    assert ended.finish == "eos"


def test_vllm_answers_cut_by_length_or_a_stop_string():
    cut = Vllm().reply(_vllm_answer("The Unreliable Ass", [504, 810, 257, 26667, 2439], "length", None, cached=None))
    assert (cut.tokens, cut.finish, cut.evaluated) == ([504, 810, 257, 26667, 2439], "length", None)
    # (no cached tokens said: a server started without --enable-prompt-tokens-details)
    stopped = Vllm().reply(_vllm_answer("The Unreliable Assassin: A Tale of Two Cities",
                                        [504, 810, 257, 26667, 2439, 520, 254, 42, 330, 30379, 282, 5713, 20281, 198,
                                         198], "stop", "\n\n"))
    assert stopped.finish == "stop" and stopped.tokens is None  # the ids run past the text: the planner spells it


def test_a_vllm_request_carries_the_grammar_token_ids_and_the_planners_sampling():
    path, body = Vllm().completion([1, 2, 3], 'root ::= "a"\n', 8, 0.0, 7, [], -1, [42, 9])
    assert path == "/v1/completions"
    assert body["prompt"] == [1, 2, 3] and body["return_token_ids"] is True
    assert body["structured_outputs"] == {"grammar": 'root ::= "a"\n'}
    assert body["logit_bias"] == {"42": -100.0, "9": -100.0}
    assert (body["top_k"], body["top_p"], body["min_p"], body["repetition_penalty"]) == (0, 1.0, 0.0, 1.0)
    assert "structured_outputs" not in Vllm().completion([1], None, 8, 0.0, 7, ["\n\n"], -1, [])[1]


class Answers:
    """A connection whose GETs are answered from a table (what a server would answer; else 404)."""

    url = "http://gpu-box:8000"

    def __init__(self, table: dict[str, object]):
        self.table, self.asked = table, []

    def call(self, method, path, body=None):
        self.asked.append(path)
        return (200, self.table[path]) if path in self.table else (404, {"detail": "Not Found"})


VLLM_MODELS = {"object": "list", "data": [{"id": "/models/smollm2", "object": "model", "owned_by": "vllm",
                                           "root": "/models/smollm2", "max_model_len": 8192}]}


def test_each_server_is_recognized_by_what_it_says_of_itself():
    props = {"default_generation_settings": {"n_ctx": 4096}, "total_slots": 4, "model_path": "/m/70b.gguf"}
    dialect, served = probe(Answers({"/props": props, "/v1/models": {"data": [{"id": "x", "owned_by": "llamacpp"}]}}))
    assert isinstance(dialect, LlamaServer) and (served.model, served.context, served.slots) == ("/m/70b.gguf", 4096, 4)
    connection = Answers({"/v1/models": VLLM_MODELS})
    dialect, served = probe(connection)
    assert isinstance(dialect, Vllm) and (served.model, served.context, served.slots) == ("/models/smollm2", 8192, 1)
    assert connection.asked.count("/v1/models") == 1  # each path asked once, whichever dialect reads it
    dialect, served = probe(Answers({"/v1/models": {"data": [{"id": "/m/a.gguf", "owned_by": "me"}]}}))
    assert isinstance(dialect, LlamaCppPythonServer) and served.model == "/m/a.gguf" and served.context is None


def test_a_server_whose_grammar_field_the_planner_does_not_know_is_refused():
    with pytest.raises(UserError, match="OpenAI-compatible server, but not one whose grammar field.*SGLang"):
        probe(Answers({"/v1/models": {"data": [{"id": "qwen", "owned_by": "sglang"}]}}))
    with pytest.raises(UserError, match="neither as llama-server .* nor as an OpenAI-compatible"):
        probe(Answers({}))


def test_a_vllm_older_than_structured_outputs_is_refused_before_it_could_plan_unconstrained():
    # vLLM before 0.12 reads guided_grammar and ignores structured_outputs, answering without a grammar
    with pytest.raises(UserError, match=r"http://gpu-box:8000 is vLLM, but version 0\.11\.2 .*upgrade vLLM"):
        probe(Answers({"/v1/models": VLLM_MODELS, "/version": {"version": "0.11.2"}}))
    for version in ({"version": "0.12.1.dev5+gabc.cpu"}, {"version": "0.32.0"}, {"version": "nightly"}, None):
        table = {"/v1/models": VLLM_MODELS} | ({"/version": version} if version else {})
        assert isinstance(probe(Answers(table))[0], Vllm)  # what cannot be read as older is not refused
