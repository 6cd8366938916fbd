"""Drafts from the context: what is looked up, and that the llama.cpp backend keeps only the drafts the model
chooses (a real GGUF model whose logits do not move with the batch, so drafts change no output)."""

from __future__ import annotations

import pytest

from smartllm_local.planner.backends.drafts import ROWS, draft_size, lookup
from smartllm_local.planner.decoding.grammar import Grammar, chars, rep, seq
from smartllm_local.planner.decoding.sampling import Sampling


def test_the_tokens_after_the_latest_earlier_occurrence_are_drafted():
    history = [1, 2, 3, 9, 1, 2, 3, 7, 8, 5, 1, 2, 3]
    assert lookup(history, 2) == [7, 8]  # the latest occurrence of 1 2 3 before the end, not the first
    assert lookup(history, 10) == [7, 8, 5, 1, 2, 3]  # as many as follow


def test_the_longest_end_that_occurred_before_decides():
    # 4 5 occurred once (followed by 6); 5 alone more lately (followed by 0)
    assert lookup([4, 5, 6, 5, 0, 4, 5], 1) == [6]
    assert lookup([4, 5, 6, 5, 0, 3, 5], 1) == [0]


def test_nothing_is_drafted_where_the_last_token_is_new_or_none_are_wanted():
    assert lookup([1, 2, 3, 4], 3) == []
    assert lookup([1, 2, 1], 0) == []
    assert lookup([7], 3) == []


def test_a_match_across_two_tokens_bytes_is_not_an_occurrence():
    # 256 = 00 01 00 00 and 1 = 01 00 00 00 (little-endian int32): the bytes of [256, 0] hold those of the
    # token 1 one byte in, which is not an earlier 1.
    assert lookup([256, 0, 9, 1], 2) == []
    assert lookup([1, 7, 256, 0, 9, 1], 1) == [7]


def test_a_short_batch_is_filled_up_to_its_rows_and_a_long_one_not_at_all():
    assert [n + draft_size(n) for n in range(1, ROWS + 1)] == [ROWS] * ROWS
    assert [draft_size(n) for n in range(ROWS, 40)] == [0] * (40 - ROWS)


PROMPT = ("def subtask1_wash_apple():\n    # go to the apple\n    GoToObject('Apple')\n    # lift it\n"
          "    PickupObject('Apple')\n    # carry it to the sink\n    GoToObject('Sink')\n") * 6 \
    + "def subtask2_wash_cup():\n"
LINE = Grammar({"root": seq("    ", rep(chars("abcdefghijklmnopqrstuvwxyz#'()_ ABCDEFGHIJKLMNOPQRSTUVWXYZ"), 1, 40),
                           "\n")})


@pytest.fixture(scope="module")
def undrafted():
    from smartllm_local.planner.backends.llamacpp import LlamaCppBackend
    from smartllm_local.planner.models import resolve_gguf

    backend = LlamaCppBackend(resolve_gguf("smollm2"), n_ctx=4096, drafts=False)
    yield backend
    backend.close()


def write(backend, lines: int) -> tuple[str, int]:
    """``lines`` greedy lines under a grammar after the prompt, each a generate call as a stage makes them; and
    the drafts the model chose."""
    context, kept = backend.tokenize(PROMPT, bos=True), backend.kept_drafts
    text = ""
    for _ in range(lines):
        out = backend.generate(context, grammar=LINE, max_tokens=LINE.max_length() + 1, sampling=Sampling())
        context, text = context + out.tokens, text + out.text
    return text, backend.kept_drafts - kept


def test_drafts_the_model_chooses_are_kept_and_change_no_output(smollm2, undrafted):
    drafted, kept = write(smollm2, 4)
    plain, none = write(undrafted, 4)
    assert drafted == plain and drafted.count("\n") == 4
    assert kept > 5 and none == 0


def test_a_kept_state_holds_the_context_and_no_drafts(smollm2, undrafted):
    """A state snapshotted for the prefix store is the context's alone: the drafts after it are taken out."""
    context = smollm2.tokenize(PROMPT, bos=True)
    for backend in (smollm2, undrafted):
        backend.prefill(context, ())
    assert smollm2._ahead  # the prompt's end was looked up: drafts follow it in the cache
    assert smollm2._snapshot() == undrafted._snapshot()


def test_tokens_added_wait_for_the_next_context_and_go_in_one_batch(smollm2, monkeypatch):
    """What one generate call adds last (a line's last token) and what the next call's context adds after it are
    evaluated together when logits are next asked for: one batch, not one each."""
    context = smollm2.tokenize(PROMPT, bos=True)
    smollm2.prefill(context, ())
    batches: list[list[int]] = []
    decode = smollm2._decode
    monkeypatch.setattr(smollm2, "_decode", lambda tokens, start, first_row: batches.append(list(tokens))
                        or decode(tokens, start, first_row))
    word, more = smollm2.tokenize_continuation(" zebra"), smollm2.tokenize_continuation(" crossing the road\n")
    smollm2.evaluate(word)  # no draft foresaw it: the prompt never names a zebra
    smollm2.sync(context + word + more)
    assert batches == []
    smollm2.next_logits()
    assert len(batches) == 1 and batches[0][:len(word + more)] == word + more


def test_no_drafts_reaches_the_backend_and_the_commands_a_run_passes_on():
    """``--no-drafts`` loads a backend that evaluates each token as the loop adds it, and ``bench``'s benchmark run
    and the parallel workers get the option back."""
    from smartllm_local.cli.options import ModelOptions

    assert "--no-drafts" not in ModelOptions(model="smollm2").as_arguments()
    options = ModelOptions(model="smollm2", no_drafts=True)
    assert "--no-drafts" in options.as_arguments()
    backend = options.load("off")
    try:
        context = backend.tokenize(PROMPT, bos=True)
        backend.generate(context, grammar=LINE, max_tokens=LINE.max_length() + 1, sampling=Sampling())
        assert backend.drafted_tokens == backend.kept_drafts == 0
    finally:
        backend.close()
