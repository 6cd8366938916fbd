#!/usr/bin/env python
"""What the grammar costs per token: llama.cpp's grammar asked about the likeliest token, then the 64
likeliest (the in-process backend's way), against an llguidance token mask over the whole
vocabulary, on the same grammars, the same logits and the same steps.

The decomposition stage is planned for a few tasks with the llama.cpp backend; at every step the
model chooses a token, the same step is also done with llguidance (its mask computed, the best
admitted token taken), and both choices are compared. Each line's grammar is also compiled by both
(llama.cpp's sampler, llguidance's matcher). Forced text is consumed by both. Reported per model:
microseconds per step and per line compile for each engine (in brackets: finding the 64 likeliest
tokens alone, which the backend does only when the likeliest is refused, and llguidance's mask
alone, before it is applied to the logits), how often the llama.cpp path had to
mask the whole vocabulary, whether the two always chose the same token, and the model's own time
per decoded token for scale.

Usage::

    python scripts/bench_masks.py [--models smollm2,gemma3-270m] [--tasks kitchen-01,living-06,bedroom-02]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from smartllm_local.benchmark.tasks import find_task, load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.planner.backends.llamacpp import LlamaCppBackend
from smartllm_local.planner.models import resolve_gguf
from smartllm_local.planner.pipeline import Planner, PlanResult
from smartllm_local.planner.prompting.scene_context import scene_objects


class Measured(LlamaCppBackend):
    """The llama.cpp backend, timing its grammar work and doing each step again with llguidance."""

    def __init__(self, path, **kwargs):
        super().__init__(path, **kwargs)
        import llguidance
        import llguidance.llamacpp

        self.llg = llguidance
        self.ll_tokenizer = llguidance.llamacpp.lltokenizer_from_vocab(self._vocab)
        self.times = {"cpp_step": 0.0, "llg_step": 0.0, "cpp_compile": 0.0, "llg_compile": 0.0, "eval": 0.0,
                      "llg_mask": 0.0, "scan": 0.0}
        self.steps = self.lines = self.full_masks = self.disagreements = self.evaluated = 0
        self._matcher = None

    def generate(self, context, *, grammar, **kwargs):
        if grammar is not None:
            started = time.perf_counter()
            self._matcher = self.llg.LLMatcher(self.ll_tokenizer, self.llg.grammar_from("gbnf", grammar.to_gbnf()))
            self.times["llg_compile"] += time.perf_counter() - started
            if self._matcher.is_error():
                raise RuntimeError(self._matcher.get_error())
            self.lines += 1
        return super().generate(context, grammar=grammar, **kwargs)

    def _grammar_sampler(self, grammar):
        started = time.perf_counter()
        sampler = super()._grammar_sampler(grammar)
        self.times["cpp_compile"] += time.perf_counter() - started
        return sampler

    def _masked(self, sampler, logits):
        self.full_masks += 1
        return super()._masked(sampler, logits)

    def _pick(self, logits, sampler, sampling, rng):
        started = time.perf_counter()
        token = super()._pick(logits, sampler, sampling, rng)
        self.times["cpp_step"] += time.perf_counter() - started
        if sampler is not None:
            started = time.perf_counter()
            mask = self._matcher.compute_bitmask()
            masked = time.perf_counter()
            bits = np.frombuffer(mask, dtype=np.uint8)
            allowed = np.unpackbits(bits, bitorder="little")[: self.n_vocab].astype(bool)
            theirs = int(np.argmax(np.where(allowed, logits, -np.inf)))
            self.times["llg_mask"] += masked - started
            self.times["llg_step"] += time.perf_counter() - started
            started = time.perf_counter()
            np.argpartition(-logits, 64)
            self.times["scan"] += time.perf_counter() - started
            self.steps += 1
            self.disagreements += theirs != token
            if not self.llama_eog(token):
                self._matcher.consume_token(token)
        return token

    def llama_eog(self, token: int) -> bool:
        return bool(self._lib.llama_vocab_is_eog(self._vocab, token))

    def _forced_tokens(self, matcher, sampler):
        tokens = super()._forced_tokens(matcher, sampler)
        if tokens and self._matcher is not None:
            self._matcher.consume_tokens(tokens)
        return tokens

    def _evaluate(self, tokens):
        started = time.perf_counter()
        super()._evaluate(tokens)
        if len(tokens) == 1:
            self.times["eval"] += time.perf_counter() - started
            self.evaluated += 1


def measure(model: str, task_ids: list[str]) -> dict:
    catalogue = load_domain().catalogue
    backend = Measured(resolve_gguf(model), n_ctx=4096)
    try:
        planner = Planner(backend, catalogue)
        for task in (find_task(load_tasks(), t) for t in task_ids):
            result = PlanResult(task.instruction, task.floor_plan, list(task.robots))
            planner.decompose(result, scene_objects(task.floor_plan))
    finally:
        backend.close()
    per = lambda key, n: round(1e6 * backend.times[key] / max(1, n), 1)  # noqa: E731
    return {"steps": backend.steps, "lines": backend.lines, "full_vocabulary_masks": backend.full_masks,
            "different_choices": backend.disagreements,
            "us_per_step": {"llamacpp_top64": per("cpp_step", backend.steps),
                            "llguidance": per("llg_step", backend.steps),
                            "top64_scan": per("scan", backend.steps),
                            "llguidance_mask": per("llg_mask", backend.steps)},
            "us_per_line_compile": {"llamacpp": per("cpp_compile", backend.lines),
                                    "llguidance": per("llg_compile", backend.lines)},
            "us_per_decoded_token": per("eval", backend.evaluated)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--models", default="smollm2,gemma3-270m")
    parser.add_argument("--tasks", default="kitchen-01,living-06,bedroom-02")
    args = parser.parse_args()
    print(f"{'model':<14}{'steps':>7}{'llama.cpp us (top-64)':>23}{'llguidance us (mask)':>22}{'full masks':>12}"
          f"{'differ':>8}{'compile us (cpp / llg)':>24}{'decode us/token':>17}")
    for model in args.models.split(","):
        found = measure(model, args.tasks.split(","))
        step, compile_ = found["us_per_step"], found["us_per_line_compile"]
        top64 = f"{step['llamacpp_top64']} ({step['top64_scan']})"
        llg = f"{step['llguidance']} ({step['llguidance_mask']})"
        print(f"{model:<14}{found['steps']:>7}{top64:>23}{llg:>22}"
              f"{found['full_vocabulary_masks']:>12}{found['different_choices']:>8}"
              f"{str(compile_['llamacpp']) + ' / ' + str(compile_['llguidance']):>24}"
              f"{found['us_per_decoded_token']:>17}")


if __name__ == "__main__":
    main()
