"""Where llama.cpp's grammar and the planner's own disagree, generation stops with an error that names the
stage and the text; no plan is built on it (and the process does not abort)."""

from __future__ import annotations

import numpy as np
import pytest

from smartllm_local.errors import GrammarMismatchError
from smartllm_local.planner.decoding.grammar import Grammar, alt
from smartllm_local.planner.decoding.sampling import Generated, Sampling
from smartllm_local.planner.result import StageRecord
from smartllm_local.planner.stages import Fitted, run_stage
from tests.planner.fakes import FakeBackend, Script


class Diverging(Grammar):
    """A grammar that tells llama.cpp other rules than the planner's own matcher follows."""

    def __init__(self, root, gbnf: str):
        super().__init__({"root": root})
        self._gbnf = gbnf

    def to_gbnf(self) -> str:
        return self._gbnf


# The planner allows Rome or Madrid; llama.cpp is told Paris or London.
LAX = Diverging(alt(" Rome.\n", " Madrid.\n"), 'root ::= " Paris.\\n" | " London.\\n"\n')
# The planner forces "    GoToObject('"; llama.cpp allows only PickupObject.
STRICT = Diverging(alt("    GoToObject('Apple')\n", "    GoToObject('Bread')\n"),
                   'root ::= "    PickupObject(\'Apple\')\\n"\n')


def test_text_llama_cpp_admits_and_the_planner_does_not_is_an_error(smollm2):
    context = smollm2.tokenize("The capital of France is", bos=True)
    with pytest.raises(GrammarMismatchError, match="Paris|London") as caught:
        smollm2.generate(context, grammar=LAX, max_tokens=10, sampling=Sampling())
    assert "planner's grammar does not allow" in str(caught.value)


def test_forced_text_llama_cpp_refuses_is_an_error_not_an_abort(smollm2):
    context = smollm2.tokenize("def wash():\n", bos=True)
    with pytest.raises(GrammarMismatchError, match="GoToObject"):
        smollm2.generate(context, grammar=STRICT, max_tokens=30, sampling=Sampling())


class Lying:
    """The real backend, told another grammar than the one a stage gives it (its rules, as ``grammar`` tells
    them to llama.cpp)."""

    def __init__(self, backend, grammar: Diverging):
        self._backend, self._gbnf = backend, grammar.to_gbnf()

    def __getattr__(self, name):
        return getattr(self._backend, name)

    def generate(self, context, *, grammar, **kwargs):
        told = Diverging(grammar.rules["root"], self._gbnf)
        return self._backend.generate(context, grammar=told, **kwargs)


@pytest.mark.parametrize("grammar, text", [(LAX, "Paris|London"), (STRICT, "GoToObject")])
def test_a_stage_names_itself_and_the_text(smollm2, grammar, text):
    record = StageRecord("decomposition")
    with pytest.raises(GrammarMismatchError, match=f"^decomposition stage: .*({text})"):
        run_stage(record, Lying(smollm2, grammar), Fitted("", smollm2.tokenize("The capital of France is", bos=True)),
                  Script(grammar), output_budget=100, sampling=Sampling(), rng=np.random.default_rng(0))
    assert record.output == ""


class Stray(FakeBackend):
    """A backend that writes a line the grammar never offered."""

    def generate(self, context, *, grammar, max_tokens, sampling, stop=(), rng=None, lines=1) -> Generated:
        return Generated([0, 0], "oops\n", "line")


def test_a_line_the_grammar_did_not_offer_is_an_error_naming_the_stage_and_the_line():
    record = StageRecord("coalition")
    with pytest.raises(GrammarMismatchError, match=r"^coalition stage: .*'oops\\n'"):
        run_stage(record, Stray(), Fitted("", [0]), Script(Grammar({"root": alt("# fine\n", "# good\n")})),
                  output_budget=100, sampling=Sampling(), rng=np.random.default_rng(0))
