"""Instruct models: a stage's prompt as the user turn of the model's own chat template.

An instruct model was trained on prompts that arrive wrapped in its chat
template, its answers in the assistant turn: so it gets each stage's prompt as
the user turn, the assistant turn opened for the output (the stage's grammar is
unchanged). The template is the model's own
(GGUF ``tokenizer.chat_template``, or a tokenizer's ``chat_template``), rendered
with the sandboxed jinja2 environment llama-cpp-python uses for chat.

The template's text is tokenized with its control tokens parsed as special
tokens (``<|im_start|>`` becomes one token id), the prompt on its own without:
a prompt that contains ``<|im_start|>`` as text stays text. The two token lists
are joined, never the strings.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

from jinja2 import TemplateError

from ...errors import ModelError, UserError
from ..backends.base import Backend
from ..models import RAW_COMPLETION
from .prompts import Prompt

CHAT_TEMPLATE_MODES = ("auto", "on", "none")

#: What a stage record says about the template (``chat_template`` in timings.json and result.json).
APPLIED, BASE_MODEL, OFF = "applied", "none (base model)", "off"

# Stands for the prompt while the template is rendered, so the template's own text can be told apart.
_PLACEHOLDER = "\x00smartllm-local prompt\x00"

# A Markdown code block: its opening fence (with or without a language), its text, and its closing fence or the
# answer's end (an answer cut inside its block).
_FENCED = re.compile(r"^```[^`\n]*\n(.*?)(?:^```|\Z)", re.S | re.M)

# How a template fails: jinja2's errors, and what its expressions raise (raise_exception gives ValueError).
_TEMPLATE_ERRORS = (TemplateError, ValueError, TypeError, KeyError)


@dataclass(frozen=True)
class ChatTurn:
    """A prompt rendered as a user turn: the template's text before it, the prompt as the template
    writes it (some templates trim it), and the template's text after it (the assistant header)."""

    head: str
    body: str
    tail: str

    @property
    def text(self) -> str:
        return self.head + self.body + self.tail


class ChatFormat:
    """A model's chat template, ready to wrap prompts."""

    def __init__(self, template: str, *, bos_token: str, eos_token: str):
        from llama_cpp.llama_chat_format import Jinja2ChatFormatter

        try:
            self._formatter = Jinja2ChatFormatter(template, eos_token=eos_token, bos_token=bos_token,
                                                  add_generation_prompt=True)
        except _TEMPLATE_ERRORS as exc:
            raise ModelError(f"the model's chat template is not a valid template ({exc}); "
                             "use --chat-template none") from exc
        self.head, self.tail = self._split(_PLACEHOLDER, self._render(_PLACEHOLDER))

    def _render(self, prompt: str) -> str:
        try:
            return self._formatter(messages=[{"role": "user", "content": prompt}]).prompt
        except _TEMPLATE_ERRORS as exc:
            raise ModelError(f"the model's chat template cannot render a prompt ({exc}); "
                             "use --chat-template none") from exc

    @staticmethod
    def _split(prompt: str, rendered: str) -> tuple[str, str]:
        if rendered.count(prompt) != 1:
            raise ModelError("the model's chat template does not write the user's message once; "
                             "use --chat-template none")
        head, tail = rendered.split(prompt)
        return head, tail

    def turn(self, prompt: str) -> ChatTurn:
        """``prompt`` as the user turn, followed by the opening of the assistant turn."""
        rendered = self._render(prompt)
        if not (rendered.startswith(self.head) and rendered.endswith(self.tail)
                and len(rendered) >= len(self.head) + len(self.tail)):
            raise ModelError("the model's chat template writes different text around different prompts; "
                             "use --chat-template none")
        return ChatTurn(self.head, rendered[len(self.head): len(rendered) - len(self.tail)], self.tail)


def check_mode(mode: str) -> None:
    """A bad ``--chat-template`` is the user's to fix, before any model is loaded."""
    if mode not in CHAT_TEMPLATE_MODES:
        raise UserError(f"--chat-template must be one of {', '.join(CHAT_TEMPLATE_MODES)}, not {mode!r}")


def mode_for(model: str | None, mode: str) -> str:
    """The mode a model is planned with: ``auto`` is ``none`` for the embedded models measured better raw
    (``on`` gives them their template); ``model`` None is one not known here (a server's own)."""
    check_mode(mode)
    return "none" if mode == "auto" and model in RAW_COMPLETION else mode


def chat_format(backend: Backend, mode: str) -> tuple[ChatFormat | None, str]:
    """The chat format a planner applies with ``--chat-template mode``, and what to record about it.

    ``auto`` and ``on`` apply the model's template when it has one (``auto`` is first resolved by
    :func:`mode_for`); a base model (no template) gets its prompts as raw text, as does every model with
    ``none``.
    """
    check_mode(mode)
    if mode == "none":
        return None, OFF
    if not backend.chat_template:
        return None, BASE_MODEL
    return ChatFormat(backend.chat_template, bos_token=backend.bos_token, eos_token=backend.eos_token), APPLIED


def prompt_tokens(backend: Backend, prompt: Prompt | str,
                  chat: ChatFormat | None) -> tuple[str, list[int], tuple[int, ...]]:
    """The text a model is given for ``prompt``, its tokens, and where each of its shared prefixes ends
    in them (none for a plain string): raw (after the model's BOS token), or as a chat turn, where the
    template decides about BOS (as llama-cpp-python's chat does).

    The first prefix is tokenized on its own and each later part as the continuation of what precedes
    it, so a prefix's tokens are the same whatever follows them."""
    parts = prompt.parts if isinstance(prompt, Prompt) else (prompt,)
    prefixes, own = parts[:-1], parts[-1]
    if chat is None:
        if not prefixes:
            return own, backend.tokenize(own, bos=True), ()
        tokens, bounds = _prefix_tokens(backend, backend.tokenize(prefixes[0], bos=True), prefixes[1:])
        return "".join(parts), tokens + backend.tokenize_continuation(own), bounds
    turn = chat.turn("".join(parts))
    start, tail = backend.tokenize(turn.head, special=True), backend.tokenize(turn.tail, special=True)
    shared = "".join(prefixes)
    if prefixes and turn.body.startswith(shared) and len(turn.body) > len(shared):  # the template kept it as is
        tokens, bounds = _prefix_tokens(backend, start + backend.tokenize(prefixes[0]), prefixes[1:])
        return turn.text, tokens + backend.tokenize_continuation(turn.body[len(shared):]) + tail, bounds
    return turn.text, start + backend.tokenize(turn.body) + tail, ()


def _prefix_tokens(backend: Backend, head: list[int], rest: tuple[str, ...]) -> tuple[list[int], tuple[int, ...]]:
    """The tokens of a prompt's prefixes, given the first's, and the position where each ends."""
    tokens, bounds = list(head), [len(head)]
    for part in rest:
        tokens += backend.tokenize_continuation(part)
        bounds.append(len(tokens))
    return tokens, tuple(bounds)


def answer_code(answer: str, stops: Sequence[str]) -> str:
    """The plan in a chat model's free answer (``--no-grammar``): in its chat turn an instruct model answers in
    prose around Markdown code blocks, so the blocks are what is read, joined, and cut where the stage's first
    stop string appears in them, as a raw completion is cut; an answer with no block is read whole."""
    blocks = _FENCED.findall(answer)
    code = "".join(block if block.endswith("\n") else block + "\n" for block in blocks) if blocks else answer
    code = code[:min((code.find(stop) for stop in stops if stop in code), default=len(code))]
    return code.rstrip() + "\n"
