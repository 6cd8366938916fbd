"""The llama.cpp backend with real GGUF models: constraints bite, sampling is reproducible, the cache is reused."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from smartllm_local.errors import ModelError
from smartllm_local.planner.backends import load_backend
from smartllm_local.planner.decoding.grammar import Grammar, GrammarError, alt, chars, rep, seq
from smartllm_local.planner.decoding.loop import Choice
from smartllm_local.planner.decoding.sampling import Sampling
from tests.planner.decoding.test_repetition import check_loop_guard

PROMPT = "The capital of France is"


def ends(backend) -> np.ndarray:
    """The backend's end-of-sequence tokens, marked over its vocabulary (aligned decoding: always the model's)."""
    marked = np.zeros(backend.n_vocab, dtype=bool)
    marked[list(backend.end_tokens)] = True
    return marked


def test_unconstrained_and_constrained_greedy_differ_and_the_grammar_wins(smollm2):
    context = smollm2.tokenize(PROMPT, bos=True)
    free = smollm2.generate(context, grammar=None, max_tokens=4, sampling=Sampling())
    assert "Paris" in free.text
    grammar = Grammar({"root": alt(" London.\n", " Rome.\n", " Madrid.\n")})
    forced = smollm2.generate(context, grammar=grammar, max_tokens=grammar.max_length() + 1, sampling=Sampling())
    assert forced.text in (" London.\n", " Rome.\n", " Madrid.\n")
    assert forced.stop == "line"


@pytest.mark.parametrize("choices", [
    (" Paris.\n", " Rome.\n"),  # the likeliest token is admitted
    (" London.\n", " Rome.\n"),  # it is not; one of the 64 likeliest is
    ("zqxj\n", "QQQ\n"),  # none of the 64 likeliest is: the whole vocabulary is masked
])
def test_greedy_under_a_grammar_picks_what_a_full_mask_picks(smollm2, choices):
    """The shortcuts (the likeliest token first, then the 64 likeliest) choose the token the grammar's mask
    over the whole vocabulary gives, in each of the three ways a choice is made."""
    import numpy as np

    grammar = Grammar({"root": alt(*choices)})
    smollm2.sync(smollm2.tokenize(PROMPT, bos=True))
    logits = smollm2.next_logits()
    top = set(np.argsort(-logits)[:64].tolist())
    constraint = smollm2.constrain(grammar)
    try:
        choice = Choice(constraint, ends(smollm2), Sampling(), np.random.default_rng(0))
        full = choice.masked(logits)
        allowed = set(np.flatnonzero(np.isfinite(full)).tolist())
        way = "first" if int(np.argmax(logits)) in allowed else "top" if allowed & top else "full"
        assert way == {" Paris.\n": "first", " London.\n": "top", "zqxj\n": "full"}[choices[0]]
        picked = choice.choose(logits)
        assert picked == int(np.argmax(full))
    finally:
        constraint.close()


def test_sampling_is_reproducible_and_stays_in_the_grammar(smollm2):
    context = smollm2.tokenize("# a list of fruit:\n", bos=True)
    grammar = Grammar({"root": seq("# ", rep(chars("abcdefghijklmnopqrstuvwxyz "), 1, 30), "\n")})
    hot = Sampling(temperature=1.5, seed=7)
    first = smollm2.generate(context, grammar=grammar, max_tokens=40, sampling=hot)
    again = smollm2.generate(context, grammar=grammar, max_tokens=40, sampling=hot)
    other = [smollm2.generate(context, grammar=grammar, max_tokens=40, sampling=Sampling(1.5, s)).text
             for s in range(5)]
    assert first.text == again.text
    assert len(set(other)) > 1
    assert all(grammar.matches(t) for t in [first.text, *other])


def test_a_grammar_that_may_end_lets_the_model_stop(smollm2):
    context = smollm2.tokenize("Say nothing at all.", bos=True)
    grammar = Grammar({"root": alt("", "zzzz\n")})
    out = smollm2.generate(context, grammar=grammar, max_tokens=6, sampling=Sampling())
    assert out.text in ("", "zzzz\n")


def test_a_shared_prefix_is_not_evaluated_again(smollm2):
    context = smollm2.tokenize("def subtask1_wash():\n    GoToObject('Apple')\n" * 20, bos=True)
    grammar = Grammar({"root": seq("    ", alt("PickupObject('Apple')", "GoToObject('Cup')"), "\n")})
    smollm2.generate(context, grammar=grammar, max_tokens=12, sampling=Sampling())
    before = smollm2.evaluated_tokens
    line = smollm2.generate(context, grammar=grammar, max_tokens=12, sampling=Sampling())
    longer = context + line.tokens + smollm2.tokenize("    # next\n")
    smollm2.generate(longer, grammar=grammar, max_tokens=12, sampling=Sampling())
    spent = smollm2.evaluated_tokens - before
    assert spent < 40, f"{spent} tokens evaluated for a {len(longer)}-token context"


def test_a_grammar_llama_cpp_rejects_is_an_error_not_a_crash(smollm2):
    class Broken(Grammar):
        def to_gbnf(self) -> str:
            return 'root ::= "a" missing-rule\n'

    broken = Broken({"root": "a"})
    with pytest.raises(GrammarError, match="rejected"):
        smollm2.generate(smollm2.tokenize("x", bos=True), grammar=broken, max_tokens=3, sampling=Sampling())


def test_a_context_longer_than_n_ctx_is_a_clear_error(smollm2):
    with pytest.raises(ModelError, match="does not fit"):
        smollm2.generate([1] * smollm2.n_ctx, grammar=None, max_tokens=1, sampling=Sampling())


def test_prompts_are_fitted_within_the_context_the_model_was_trained_on(smollm2):
    """SmolLM2 was trained on 8,192 tokens: a larger --n-ctx fits prompts within those, a smaller one stays."""
    assert smollm2.trained_context == 8192 and smollm2.n_ctx == 8192
    larger = load_backend("llamacpp", "smollm2", n_ctx=12288, prefix_cache="off")
    try:
        assert larger.n_ctx == 8192
    finally:
        larger.close()
    smaller = load_backend("llamacpp", "smollm2", n_ctx=2048, prefix_cache="off")
    try:
        assert smaller.n_ctx == 2048
    finally:
        smaller.close()


def test_the_other_embedded_model_runs_too():
    gemma = load_backend("llamacpp", "gemma3-270m", n_ctx=1024)
    try:
        assert gemma.n_vocab > 200_000
        grammar = Grammar({"root": seq("    ", alt("SwitchOn('Toaster')", "SwitchOff('Toaster')"), "\n")})
        out = gemma.generate(gemma.tokenize("def toast():\n", bos=True), grammar=grammar,
                             max_tokens=grammar.max_length() + 1, sampling=Sampling())
        assert grammar.matches(out.text)
    finally:
        gemma.close()


def test_the_loop_guard_ends_free_text_that_loops(smollm2):
    check_loop_guard(smollm2)


def test_forced_text_ends_with_the_models_own_token_and_a_word_keeps_its_space(smollm2):
    """Token healing: the planner writes forced text up to its last token, and the model writes on from there
    under the grammar, so the space that ends ``# SubTask 1: `` comes with the model's next word (`` put``),
    as the model tokenizes it, never doubled."""
    from smartllm_local.planner.constraints.format import SUMMARY_CHARS, text_run

    line = "# SubTask 1: put the apple in the fridge\n"
    context = smollm2.tokenize(line * 4, bos=True)
    grammar = Grammar({"root": seq("# SubTask 1: ", text_run(SUMMARY_CHARS, 40), "\n")})
    out = smollm2.generate(context, grammar=grammar, max_tokens=grammar.max_length() + 1, sampling=Sampling())
    assert out.text == line and out.tokens == smollm2.tokenize(line)
    pieces = [smollm2.detokenize([t]) for t in out.tokens]
    assert " put" in pieces and out.forced == pieces.index(" put") and out.choices == len(pieces) - out.forced
    # unaligned (--no-token-alignment), the space is forced and the model's word comes without its own
    whole = smollm2.generate(context, grammar=grammar, max_tokens=grammar.max_length() + 1,
                             sampling=Sampling(aligned=False))
    assert whole.tokens != out.tokens and " put" not in [smollm2.detokenize([t]) for t in whole.tokens]


def test_the_end_of_sequence_is_the_models_choice_where_the_grammar_cannot_end(smollm2):
    """The model ends the sequence where it would, though the line is not complete (the planner completes it
    then); with its likeliest token refused at each step, each such step is counted."""
    from smartllm_local.planner.prompting.chat import chat_format, prompt_tokens

    chat, _ = chat_format(smollm2, "auto")
    _, context, _ = prompt_tokens(smollm2, "Answer with one word: is the sky blue?", chat)
    grammar = Grammar({"root": seq(rep(chars("abcdefghijklmnopqrstuvwxyzY"), 1, 30), "\n")})
    out = smollm2.generate(context, grammar=grammar, max_tokens=40, sampling=Sampling())
    assert out.stop == "eos" and out.text and "\n" not in out.text and grammar.after(out.text)
    assert out.choices == len(out.tokens) + 1 and out.logprob < 0
    free = smollm2.generate(context, grammar=None, max_tokens=40, sampling=Sampling())
    assert free.stop == "eos" and 0 < out.refused <= out.choices


def test_an_end_of_sequence_far_down_the_models_ranking_is_not_its_choice(smollm2):
    """Where neither the end of sequence nor any token the grammar admits is among the model's 64 likeliest,
    the model goes on under the grammar, though the end is likelier than what it writes: there the end is
    only the least unlikely token left, and a server, which reports the 64 likeliest, would not see it."""
    from smartllm_local.planner.decoding.sampling import may_end

    grammar = Grammar({"root": alt("zqxj\n", "monary\n")})
    smollm2.sync(smollm2.tokenize(PROMPT, bos=True))
    logits = smollm2.next_logits()
    end = max(smollm2.end_tokens, key=lambda t: logits[t])
    constraint = smollm2.constrain(grammar)
    try:
        admitted = Choice(constraint, None, Sampling(), np.random.default_rng(0)).masked(logits)
        assert logits[end] > admitted.max() and not may_end(logits, end)  # what the case needs
        picked = Choice(constraint, ends(smollm2), Sampling(), np.random.default_rng(0)).choose(logits)
        assert picked == int(np.argmax(admitted)) and picked not in smollm2.end_tokens
    finally:
        constraint.close()


def test_a_process_that_imports_numpy_before_llama_cpp_loads_and_runs_a_model():
    """The order that crashed llama.cpp's model load on a CUDA build (docs/servers-and-gpus.md): numpy first, then a
    model loaded and run; here on the build CI has, on a GPU machine by scripts/gpu_check.sh."""
    code = ("import numpy, sys; assert 'llama_cpp' not in sys.modules\n"
            "from smartllm_local.planner.backends import load_backend\n"
            "backend = load_backend('llamacpp', 'smollm2', n_ctx=512, prefix_cache='off')\n"
            "print(len(backend.tokenize('Put the apple in the fridge')))\n")
    done = subprocess.run([sys.executable, "-X", "faulthandler", "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    assert int(done.stdout.split()[-1]) > 3


def test_scores_that_are_not_numbers_are_a_clear_error_not_a_grammar_one(smollm2):
    """A broken model or build (a random 70B shape overflowed half precision on a GPU) gives NaN logits: said so."""
    logits = np.zeros(smollm2.n_vocab, dtype=np.float32)
    logits[7] = np.nan
    with pytest.raises(ModelError, match="not numbers"):
        Choice(None, ends(smollm2), Sampling(), np.random.default_rng(0)).choose(logits)


def test_flash_attention_is_off_on_the_cpu_and_llama_cpps_auto_where_layers_are_on_a_gpu(smollm2):
    """Off on the CPU (measured slower there); on a GPU llama.cpp's own ``auto``, which llama-cpp-python cannot ask
    for by name: its "off" constant is borrowed while the context is made, and left as it was."""
    import llama_cpp

    from smartllm_local.planner.backends import llamacpp

    assert smollm2.llm.context_params.flash_attn_type == llama_cpp.LLAMA_FLASH_ATTN_TYPE_DISABLED
    with llamacpp._flash_attention_auto(llama_cpp, wanted=True):
        assert llama_cpp.llama_cpp.LLAMA_FLASH_ATTN_TYPE_DISABLED == llama_cpp.LLAMA_FLASH_ATTN_TYPE_AUTO
    assert llama_cpp.llama_cpp.LLAMA_FLASH_ATTN_TYPE_DISABLED == 0
