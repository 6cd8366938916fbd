"""Tokenization against every tokenizer family: llama.cpp's vocabulary files and the embedded models.

The vocabulary files (tests/fixtures/vocab, xz-compressed copies of llama.cpp's
models/ggml-vocab-*.gguf) hold a tokenizer and no weights: they tokenize but
cannot generate, so what depends on tokenization alone is tested here, for
Llama-2's SentencePiece tokenizer (llama-spm, the paper's model) and phi-3's,
Llama-3's byte-level BPE (llama-bpe), Qwen2's and DeepSeek-Coder's, and the
embedded SmolLM2 (GPT-2 style BPE) and Gemma-3 (SentencePiece, no added space).
"""

from __future__ import annotations

import lzma
import random
import shutil
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.planner.backends.llamacpp import LlamaCppBackend
from smartllm_local.planner.backends.server.vocabulary import end_tokens_by_rule
from smartllm_local.planner.decoding.grammar import Grammar, alt, seq
from smartllm_local.planner.decoding.loop import forced_tokens
from smartllm_local.planner.decoding.matcher import Matcher
from smartllm_local.planner.decoding.sampling import Generated, Sampling
from smartllm_local.planner.models import embedded_model_path
from smartllm_local.planner.prompting.chat import prompt_tokens
from smartllm_local.planner.prompting.prompts import (
    PromptOptions,
    allocation_prompt,
    coalition_prompt,
    decomposition_prompt,
    examples_for,
    load_examples,
)
from smartllm_local.planner.result import StageRecord
from smartllm_local.planner.stages import Fitted, run_stage
from smartllm_local.worlds import scene_objects
from tests.planner.fakes import Script

VOCAB_DIR = Path(__file__).parents[2] / "fixtures" / "vocab"
#: family -> whether its models start a sequence with a BOS token
FAMILIES = {"llama-spm": True, "phi-3": True, "llama-bpe": True, "qwen2": False, "deepseek-coder": True,
            "smollm2": False, "gemma3-270m": True}
SENTENCEPIECE = {"llama-spm", "phi-3"}  # tokenizers that put a space in front of what they tokenize

#: Pieces of forced text as plans have them: whole lines, after a newline, mid-line.
FORCED = [
    "    GoToObject(robot_list[0], 'Apple')\n", "t1.start()\n", "# SubTask 1: wash the apple (skills: GoToObject)\n",
    "def subtask1_x(robot_list):\n", "robot_list[", "], '", "')\n", " and ", "\n", "\n\n", "    ", "    # ",
    "threads = []\n", "# Task Description: put the bread in the fridge\n", "time.sleep(2)\n", "ü → é\n",
]
PLAN = (
    "# SubTask 1: wash the apple (skills: GoToObject, PickupObject)\n"
    "# wash first\n\n"
    "def subtask1_wash_apple(robot_list):\n"
    "    # go to the apple\n"
    "    GoToObject(robot_list[0], 'Apple')\n"
    "    PickupObject(robot_list[0], 'Apple')\n\n"
    "t1 = threading.Thread(target=subtask1_wash_apple, args=([robots[0], robots[1]],))\n"
    "t1.start()\n"
    "t1.join()\n"
)


@pytest.fixture(scope="module", params=sorted(FAMILIES))
def vocab(request, tmp_path_factory) -> Iterator[LlamaCppBackend]:
    """A backend with only the tokenizer of a family loaded."""
    family = request.param
    if family in ("smollm2", "gemma3-270m"):
        path = embedded_model_path(family)
    else:
        path = tmp_path_factory.mktemp("vocab") / f"ggml-vocab-{family}.gguf"
        with lzma.open(VOCAB_DIR / f"ggml-vocab-{family}.gguf.xz") as packed, path.open("wb") as out:
            shutil.copyfileobj(packed, out)
    backend = LlamaCppBackend(path, n_ctx=512, vocab_only=True)
    backend.family = family
    yield backend
    backend.close()


def test_forced_text_is_spelled_exactly_as_a_continuation(vocab):
    for text in FORCED:
        tokens = vocab.tokenize_continuation(text)
        assert vocab.detokenize(tokens) == text, (vocab.family, text)
        assert 0 < len(tokens) <= len(text.encode())


def test_a_plan_written_piece_by_piece_spells_itself(vocab):
    """Forced pieces and lines of a plan, each a continuation of the last, spell the whole plan."""
    pieces = [p for line in PLAN.splitlines(keepends=True) for p in line.partition("(")]
    tokens = [t for piece in pieces for t in vocab.tokenize_continuation(piece)]
    assert vocab.detokenize(tokens) == PLAN
    assert vocab.detokenize(vocab.tokenize_continuation(PLAN)) == PLAN
    whole = vocab.tokenize(PLAN)
    assert len(tokens) <= 1.25 * len(whole), (len(tokens), len(whole))  # the cuts cost a few tokens, no more


def test_standalone_tokens_spell_a_text_only_where_the_tokenizer_adds_no_space(vocab):
    """What made forced text fall back to token-by-token generation for Llama-2 before."""
    text = "    GoToObject(robot_list[0], 'Apple')\n"
    spelled = vocab.detokenize(vocab.tokenize(text))
    assert spelled == (" " + text if vocab.family in SENTENCEPIECE else text)


def test_a_prompt_starts_with_bos_only_where_the_model_uses_one(vocab):
    prompt = "# Task Description: put the bread in the fridge\n"
    tokens = vocab.tokenize(prompt, bos=True)
    bos = [vocab.llm.token_bos()] if FAMILIES[vocab.family] else []
    assert tokens == bos + vocab.tokenize(prompt)
    assert tokens[-1] != vocab.llm.token_eos()
    assert vocab.detokenize(tokens) == (" " + prompt if vocab.family in SENTENCEPIECE else prompt)


def test_the_grammars_forced_text_goes_in_one_batch_but_its_last_token(vocab):
    """The decision generate takes, without generating: the forced text's tokens, all at once, accepted by
    llama.cpp's grammar, but the last, which the model writes (token healing); whole, unaligned."""
    forced = "    GoToObject(robot_list[0], '"
    grammar = Grammar({"root": seq(forced, alt("Apple", "Bread"), "')\n")})
    matcher = Matcher(grammar)
    whole = vocab.tokenize_continuation(forced)
    for heal, expected in ((True, whole[:-1]), (False, whole)):
        tokens = forced_tokens(matcher.forced(), vocab.tokenize_continuation, heal=heal)
        constraint = vocab.constrain(grammar)
        try:
            assert tokens == expected and all(constraint.accept(t) for t in tokens)
        finally:
            constraint.close()
    assert matcher.advance(forced)
    assert forced_tokens(matcher.forced(), vocab.tokenize_continuation, heal=True) == []


def test_a_mask_asked_of_the_tokens_that_begin_with_a_character_admitted_next_is_the_whole_vocabularys(vocab):
    """What lets a whole-vocabulary mask ask llama.cpp's grammar about a few tokens (planner/decoding/first_bytes.py),
    for every tokenizer family (SentencePiece's pieces begin with their space)."""
    grammar = Grammar({"root": seq("    ", alt("GoToObject(", "PickupObject(", "# fetch it"), "'Apple')\n")})
    matcher, constraint = Matcher(grammar), vocab.constrain(grammar)
    logits = np.random.default_rng(0).normal(size=vocab.n_vocab).astype(np.float32)
    try:
        for piece in ("", "    ", "Go"):
            assert matcher.advance(piece) and all(constraint.accept(t) for t in vocab.tokenize_continuation(piece))
            ids = vocab.first_bytes().starting_with(matcher.next_chars())
            narrowed = np.full(vocab.n_vocab, -np.inf, dtype=np.float32)
            narrowed[ids] = constraint.mask(logits[ids], ids)
            assert np.array_equal(narrowed, constraint.mask(logits)) and np.isfinite(narrowed).any()
            assert piece == "" or len(ids) < vocab.n_vocab / 8  # (where a space comes next, many tokens begin with one)
        refused = vocab.tokenize_continuation("#")[0]
        admitted = int(np.argmax(constraint.mask(logits)))
        assert constraint.admits(admitted) and not constraint.accept(refused)  # asked again: not the one just admitted
    finally:
        constraint.close()


class GrammarWriter:
    """A backend that writes each offered line from the grammar (a vocabulary cannot generate), tokenized by
    ``vocab``, and keeps the contexts it is asked to continue."""

    def __init__(self, vocab: LlamaCppBackend):
        self.vocab, self.n_ctx, self.contexts = vocab, vocab.n_ctx, []

    def __getattr__(self, name):
        return getattr(self.vocab, name)

    def prefill(self, context, shared: int) -> int:
        return 0  # a vocabulary cannot evaluate

    def generate(self, context, *, grammar, max_tokens, sampling, stop=(), rng=None, lines=1) -> Generated:
        self.contexts.append((list(context), grammar))
        text = grammar.sample(random.Random(0), "shortest")
        return Generated(self.vocab.tokenize_continuation(text), text, "line")


def test_forced_text_goes_into_the_next_line_and_what_ends_a_stage_in_one_batch(vocab):
    """Forced text is written with the line the model writes next (its last token is the model's: token
    healing); what the stage forces after its last line goes into the context in one batch, for every
    tokenizer family."""
    head, tail = "def subtask1_wash_apple(robot_list):\n", "\nt1.start()\n"
    step = "    GoToObject(robot_list, 'Apple')\n"  # the shortest of the two: what the writer writes
    offered = Grammar({"root": alt(step, step.replace("robot_list", "robot_list[0]"))})
    backend = GrammarWriter(vocab)
    prompt = vocab.tokenize("# Your plan:\n", bos=True)
    record = StageRecord("allocation")
    run_stage(record, backend, Fitted("", prompt), Script(head, offered, tail), output_budget=200,
              sampling=Sampling(), rng=np.random.default_rng(0))
    assert record.output == head + step + tail
    (context, grammar), = backend.contexts  # one generation: the offered line, the head before it
    assert context == prompt and grammar.matches(head + step) and not grammar.matches(step)
    assert vocab.detokenize(record.context[len(prompt):]) == head + step + tail
    assert record.forced_tokens == len(vocab.tokenize_continuation(tail))


def test_a_line_that_leaves_no_choice_goes_into_the_next_lines_batch(vocab):
    """A line offered with one way to write it (a step whose robot the team leaves no choice of) is not asked of
    the model: it goes into the context with the next line it writes, as forced text does."""
    head, only = "def subtask1_wash_apple(robot_list):\n", "    PickupObject(robot_list[0], 'Apple')\n"
    step = "    GoToObject(robot_list, 'Sink')\n"
    offered = Grammar({"root": alt(step, step.replace("robot_list", "robot_list[0]"))})
    backend = GrammarWriter(vocab)
    prompt = vocab.tokenize("# Your plan:\n", bos=True)
    record = StageRecord("allocation")
    run_stage(record, backend, Fitted("", prompt), Script(head, Grammar({"root": only}), offered), output_budget=200,
              sampling=Sampling(), rng=np.random.default_rng(0))
    assert record.output == head + only + step
    (context, grammar), = backend.contexts
    assert context == prompt and grammar.matches(head + only + step) and not grammar.matches(only + step)


def test_a_hugging_face_vocabulary_spells_llama2_continuations_exactly(tmp_path):
    """Hugging Face's decode drops a SentencePiece token's leading space at the start of what it decodes
    ("   GoToObject" for four spaces); the vocabulary of the transformers backend (and of a vLLM-served
    model) spells tokens by their bytes instead."""
    transformers = pytest.importorskip("transformers")
    pytest.importorskip("llguidance.hf")
    from smartllm_local.planner.backends.hf_vocabulary import HFVocabulary

    with lzma.open(VOCAB_DIR / "ggml-vocab-llama-spm.gguf.xz") as packed, (tmp_path / "spm.gguf").open("wb") as out:
        shutil.copyfileobj(packed, out)
    tokenizer = transformers.AutoTokenizer.from_pretrained(str(tmp_path), gguf_file="spm.gguf", local_files_only=True)
    vocabulary = HFVocabulary(tokenizer, "llama-spm")
    for text in FORCED:
        tokens = vocabulary.tokenize_continuation(text)
        assert vocabulary.detokenize(tokens) == text, text
    assert vocabulary.tokenize("# Task\n", bos=True)[0] == tokenizer.bos_token_id == vocabulary.bos_added()
    # what a server that takes text is sent: control tokens written out, so it reads them back as such
    prompt = vocabulary.tokenize("<s>[INST] Plan [/INST]", special=True)
    assert vocabulary.tokenize(vocabulary.text_of(prompt), special=True) == prompt


def test_a_prompt_tokenized_in_its_parts_is_tokenized_as_a_whole(vocab):
    """Every stage's prompt, for tasks of several scenes and teams: the shared examples tokenized on
    their own and each later part as the continuation give the tokens of the whole prompt, and the
    shared tokens are the same for every task, a decomposition's scene part for every task on its
    floor plan (what a kept prefix state is keyed by)."""
    catalogue, examples, options = load_domain().catalogue, load_examples(), PromptOptions()
    decomposition, coalition = examples[0].decomposition, examples[0].coalition
    shared_tokens: dict[str, set[tuple[int, ...]]] = {}
    site_tokens: dict[int, set[tuple[int, ...]]] = {}
    for task in load_tasks()[::5]:
        scene, team = scene_objects(task.floor_plan), catalogue.team(task.robots)
        prompts = {
            "decomposition": decomposition_prompt(task.instruction, scene, catalogue, team,
                                                  examples_for("decomposition", examples, options), options),
            "coalition": coalition_prompt(decomposition, team, scene, catalogue.skills, catalogue.robots,
                                          examples_for("coalition", examples, options), options),
            "coalition alone": coalition_prompt(decomposition, team, scene, catalogue.skills, catalogue.robots,
                                                examples_for("coalition", examples, options), options,
                                                allocations=False),
            "allocation": allocation_prompt(decomposition, coalition, team, catalogue.skills, catalogue.robots,
                                            examples_for("allocation", examples, options), options),
        }
        for stage, prompt in prompts.items():
            text, tokens, prefixes = prompt_tokens(vocab, prompt, None)
            assert text == prompt.text and tokens == vocab.tokenize(text, bos=True), (vocab.family, task.id, stage)
            shared = prefixes[0]
            assert vocab.detokenize(tokens[:shared]).endswith("# Your") and 0 < shared < len(tokens)
            shared_tokens.setdefault(stage, set()).add(tuple(tokens[:shared]))
            if stage == "decomposition":  # then the scene's objects, ending before the team's skills
                assert vocab.detokenize(tokens[shared:prefixes[1]]) == f" task\nobjects = {scene.python_list()}\nfrom"
                site_tokens.setdefault(task.floor_plan, set()).add(tuple(tokens[:prefixes[1]]))
            else:
                assert len(prefixes) == 1
    assert all(len(kinds) == 1 for kinds in shared_tokens.values()), vocab.family
    assert all(len(kinds) == 1 for kinds in site_tokens.values()) and len(site_tokens) > 1, vocab.family


def test_a_folder_without_a_tokenizer_is_a_clear_error(tmp_path):
    pytest.importorskip("transformers")
    from smartllm_local.errors import ModelError
    from smartllm_local.planner.backends.server.vocabulary import open_vocabulary

    (tmp_path / "config.json").write_text("{}")
    with pytest.raises(ModelError, match="holds no Hugging Face tokenizer.*tokenizer files"):
        open_vocabulary(tmp_path)


def test_a_served_vocabulary_ends_where_llama_cpp_ends(vocab):
    """A vocabulary known only through llama-server's tokenizer finds llama.cpp's end-of-generation set by its rule:
    the server path ends where the in-process backend ends."""
    assert end_tokens_by_rule(vocab.tokenize, vocab.eos_token) == vocab.end_tokens != frozenset()
