"""Model backends: llama.cpp (default), transformers (+ llguidance), and model servers. They only generate."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ...errors import SmartLLMError, UserError
from ..decoding.repetition import LoopGuard
from ..decoding.sampling import Generated, Sampling
from ..models import checkpoint_folder, resolve_gguf
from .base import Backend

BACKENDS = ("llamacpp", "transformers", "server")

__all__ = ["BACKENDS", "Backend", "Generated", "LoopGuard", "Sampling", "check_server_options", "load_backend",
           "load_backends", "model_location", "trained_context"]


def load_backend(
    name: str = "llamacpp",
    model: str | None = None,
    *,
    n_ctx: int = 8192,
    threads: int | None = None,
    n_gpu_layers: int = 0,
    seed: int = 0,
    prefix_cache: str | Path | None = None,
    drafts: bool = True,
) -> Backend:
    """Load a model in a backend; ``model`` is a path or an embedded model name (None: the default).

    ``prefix_cache``: the folder keeping the examples' key/value states for later processes (None: the
    user's cache; "off": none). llama.cpp only: transformers keeps them for its own process. ``drafts``: llama.cpp
    evaluates drafts from the context with the loop's tokens (see :mod:`.drafts`); off, each as the loop adds it.

    ``n_gpu_layers``: layers to offload to a GPU (llama.cpp, -1 for all); for transformers it is
    all-or-nothing: 0 runs on the CPU, any other value puts the whole model on the CUDA GPU.
    """
    # No network, ever: these switches keep Hugging Face libraries off the hub.
    for switch in ("HF_HUB_OFFLINE", "TRANSFORMERS_OFFLINE", "HF_DATASETS_OFFLINE"):
        os.environ[switch] = "1"
    if name == "llamacpp":
        from ..models import resolve_gguf
        from .llamacpp import LlamaCppBackend
        from .prefix_cache import open_store

        return LlamaCppBackend(resolve_gguf(model), n_ctx=n_ctx, threads=threads, n_gpu_layers=n_gpu_layers, seed=seed,
                               prefix_store=open_store(prefix_cache), drafts=drafts)
    if name == "transformers":
        from .transformers import TransformersBackend

        return TransformersBackend(model, n_ctx=n_ctx, threads=threads, n_gpu_layers=n_gpu_layers, seed=seed)
    if name == "server":
        raise UserError("the server backend needs its endpoints: load it with load_backends")
    raise UserError(f"unknown backend {name!r}; choose one of {', '.join(BACKENDS)}")


def load_backends(
    name: str,
    model: str | None = None,
    *,
    workers: int = 1,
    endpoints: Sequence[str] = (),
    server_timeout: float | None = None,
    **settings: Any,
) -> list[Backend]:
    """One backend per worker: several only for ``server``, spread over ``endpoints`` and their slots
    (``model`` is then the served GGUF or tokenizer folder, read for its vocabulary alone, or None where the
    server says its path)."""
    check_server_options(name, endpoints, workers)
    if name != "server":
        return [load_backend(name, model, **settings)]
    from .server.backend import DEFAULT_TIMEOUT, connect

    return list(connect(endpoints, model, workers=workers, n_ctx=settings.get("n_ctx", 8192),
                        timeout=server_timeout or DEFAULT_TIMEOUT))


MAX_LANES = 256  # llama.cpp's LLAMA_MAX_SEQ: the sequences one context holds (a lane is one)


def check_server_options(name: str, endpoints: Sequence[str], workers: int) -> None:
    """Endpoints belong to the server backend, which needs at least one; tasks planned at once (``--parallel``,
    ``workers`` here) need a backend that decodes several sequences together: llama.cpp's lanes or a server."""
    if name == "server" and not endpoints:
        raise UserError("--backend server needs --endpoint URL[,URL...] (a llama-server, llama_cpp.server or vLLM)")
    if name != "server" and endpoints:
        raise UserError("--endpoint is for --backend server; an in-process model needs none")
    if workers < 1:
        raise UserError(f"--parallel must be 1 or more (the tasks planned at once), not {workers}")
    if name == "llamacpp" and workers > MAX_LANES:
        raise UserError(f"--parallel {workers}: llama.cpp holds at most {MAX_LANES} sequences in a context; give "
                        f"{MAX_LANES} or fewer")
    if workers > 1 and name not in ("llamacpp", "server"):
        raise UserError(f"--parallel {workers}: the {name} backend decodes one sequence at a time; use --backend "
                        "llamacpp (a GGUF model, its K tasks' tokens evaluated in shared batches) or --backend server "
                        "(llama-server -np K), or leave out --parallel")


def model_location(name: str, model: str | None) -> Path | None:
    """The file (or checkpoint folder) a backend would load for ``--model``, found without loading it
    (None: a server's model that ``--model`` does not name)."""
    if name == "server" and model is None:
        return None
    folder = checkpoint_folder(model) if name in ("transformers", "server") else None
    return folder or resolve_gguf(model)


def trained_context(name: str, model: str | None) -> int | None:
    """The context ``--model`` was trained on, read without loading its weights (a GGUF file's metadata, a
    checkpoint's config.json). None where it cannot be known here: a served model ``--model`` does not name, a
    file that says nothing of it, or a model that cannot be found or read (loading it then says why)."""
    try:
        location = model_location(name, model)
        if location is None:
            return None
        if location.is_dir():
            from .hf_vocabulary import checkpoint_context

            return checkpoint_context(location)
        from .llamacpp import gguf_trained_context

        return gguf_trained_context(location)
    except SmartLLMError:
        return None
