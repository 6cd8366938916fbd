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

Both engines are followed through the backend's own decoding loop (:mod:`smartllm_local.planner.decoding.loop`):
llama.cpp's grammar is the backend's :class:`.LlamaGrammar`, timed where the loop asks it, llguidance's the
transformers backend's :class:`.LLGuidanceGrammar`, given the same logits and the same end-of-sequence rule. A step
where the loop guard wrote its own way out of a loop is timed but its choice not compared.

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
from smartllm_local.planner.backends.llamacpp_decoding import LlamaGrammar
from smartllm_local.planner.backends.llguidance_grammar import LLGuidanceGrammar
from smartllm_local.planner.decoding.grammar import Grammar
from smartllm_local.planner.decoding.loop import Choice
from smartllm_local.planner.decoding.sampling import Sampling
from smartllm_local.planner.models import resolve_gguf
from smartllm_local.planner.pipeline import Planner
from smartllm_local.planner.result import PlanResult


class Timed:
    """llama.cpp's grammar (:class:`.LlamaGrammar`) as the decoding loop uses it, timed, with llguidance's
    (:class:`.LLGuidanceGrammar`) followed beside it: each step the loop chooses a token, llguidance chooses one too
    from the same logits. A step runs from the model's logits to llama.cpp's last answer before the token is
    accepted; a second question about a token already answered in the step (the loop's measure of how far the grammar
    bent the model) is answered from the step's own record, untimed."""

    def __init__(self, bench: Measured, grammar: Grammar):
        self.bench, self.name = bench, LlamaGrammar.name
        started = time.perf_counter()
        self.cpp = LlamaGrammar(bench._lib, bench._vocab, bench.n_vocab, grammar)
        compiled = time.perf_counter()
        self.llg = LLGuidanceGrammar(bench.llg, bench.ll_tokenizer, bench.n_vocab, grammar)
        bench.times["cpp_compile"] += compiled - started
        bench.times["llg_compile"] += time.perf_counter() - compiled
        bench.lines += 1
        # The end of sequence is the model's to choose among its likeliest, for llguidance as for llama.cpp.
        self.llg_choice = Choice(self.llg, bench.ends, bench.sampling, np.random.default_rng(0))
        self.answers: dict[int, bool] = {}

    def _timed(self, ask):
        """``ask()``, its time counted to the step the model's logits opened (none: forced text)."""
        answer = ask()
        if self.bench.step_logits is not None:
            self.bench.step_end = time.perf_counter()
        return answer

    def admits(self, token: int) -> bool:
        if self.bench.step_logits is not None and token in self.answers:
            return self.answers[token]
        answer = self.answers[token] = self._timed(lambda: self.cpp.admits(token))
        return answer

    def mask(self, logits: np.ndarray, ids: np.ndarray | None = None) -> np.ndarray:
        self.bench.full_masks += ids is None and self.bench.step_logits is not None
        return self._timed(lambda: self.cpp.mask(logits, ids))

    def accept(self, token: int) -> bool:
        self.bench.finish_step(self, token)
        self.answers.clear()
        accepted = self.cpp.accept(token)
        if accepted and not self.llg.accept(token):
            raise RuntimeError(f"llguidance refuses token {token}, which llama.cpp's grammar accepted")
        return accepted

    def close(self) -> None:
        self.bench.finish_step(self, None)  # a sequence ended by the model: its end token is accepted by neither
        self.cpp.close()
        self.llg.close()


class Measured(LlamaCppBackend):
    """The llama.cpp backend, its grammars timed and followed by llguidance (:class:`Timed`), its single-token
    evaluations timed."""

    def __init__(self, path, **kwargs):
        super().__init__(path, **kwargs)
        import llguidance
        import llguidance.llamacpp
        import llguidance.torch  # noqa: F401  (imported here, not in the first compile it would be timed in)

        self.llg = llguidance
        self.ll_tokenizer = llguidance.llamacpp.lltokenizer_from_vocab(self._vocab)
        self.sampling = Sampling()
        self.ends = np.zeros(self.n_vocab, dtype=bool)
        self.ends[list(self.end_tokens)] = True
        self.times = {"cpp_step": 0.0, "llg_step": 0.0, "cpp_compile": 0.0, "llg_compile": 0.0, "eval": 0.0,
                      "llg_mask": 0.0, "scan": 0.0}
        self.steps = self.lines = self.full_masks = self.disagreements = self.evaluated = self.guarded = 0
        self.step_logits: np.ndarray | None = None  # the logits of the step under way (None: between steps)
        self.step_start = self.step_end = 0.0
        self.way_out = False

    def generate(self, context, *, grammar, sampling, **kwargs):
        if grammar is not None and (sampling.temperature > 0 or not sampling.aligned):
            raise SystemExit("bench_masks measures greedy, aligned decoding (the planner's default)")
        self.step_logits = None
        return super().generate(context, grammar=grammar, sampling=sampling, **kwargs)

    def constrain(self, grammar: Grammar) -> Timed:
        return Timed(self, grammar)

    def next_logits(self) -> np.ndarray:
        logits = super().next_logits()
        self.step_logits, self.way_out = logits, False
        self.step_start = self.step_end = time.perf_counter()
        return logits

    def tokenize_continuation(self, text: str) -> list[int]:
        self.way_out |= self.step_logits is not None  # the loop guard writes its way out of a loop instead
        return super().tokenize_continuation(text)

    def finish_step(self, timed: Timed, token: int | None) -> None:
        """Close the step under way, if any, at the token the loop chose (None: an end of sequence): llguidance's
        mask and choice on the same logits, the top-64 scan alone for scale."""
        logits, self.step_logits = self.step_logits, None
        if logits is None:
            return
        self.times["cpp_step"] += self.step_end - self.step_start
        started = time.perf_counter()
        timed.llg.admits(0)  # computes llguidance's mask of the whole vocabulary
        masked = time.perf_counter()
        theirs = int(np.argmax(timed.llg_choice.masked(logits)))
        self.times["llg_mask"] += masked - started
        self.times["llg_step"] += time.perf_counter() - started
        started = time.perf_counter()
        np.argpartition(-logits, 64)
        self.times["scan"] += time.perf_counter() - started
        self.steps += 1
        if self.way_out:
            self.guarded += 1  # the token is the loop guard's, not the grammar's choice: not compared
        elif token is None:
            self.disagreements += not self.ends[theirs]
        else:
            self.disagreements += theirs != token

    def evaluate(self, tokens: list[int]) -> None:
        started = time.perf_counter()
        super().evaluate(tokens)
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
            planner.decompose(result)
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
            "us_per_decoded_token": per("eval", backend.evaluated), "loop_guard_steps": backend.guarded}


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
