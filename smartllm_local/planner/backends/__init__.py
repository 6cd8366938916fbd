"""Model backends: llama.cpp (default) and transformers (+ llguidance). They only generate."""

from __future__ import annotations

import os
from pathlib import Path

from ...errors import UserError
from ..models import EMBEDDED
from .base import Backend, Generated, Sampling

BACKENDS = ("llamacpp", "transformers")

__all__ = ["BACKENDS", "Backend", "Generated", "Sampling", "load_backend", "model_location"]


def load_backend(
    name: str = "llamacpp",
    model: str | None = None,
    *,
    n_ctx: int = 4096,
    threads: int | None = None,
    n_gpu_layers: int = 0,
    seed: int = 0,
    prefix_cache: str | Path | None = None,
) -> Backend:
    """Load a model in a backend; ``model`` is a path or an embedded model name (None: the default).

    ``prefix_cache``: the folder keeping the examples' key/value states for later processes (None: the
    user's cache; "off": none). llama.cpp only: transformers keeps them for its own process.

    ``n_gpu_layers``: layers to offload to a GPU (llama.cpp, -1 for all); for transformers it is
    all-or-nothing: 0 runs on the CPU, any other value puts the whole model on the CUDA GPU.
    """
    # No network, ever: these switches keep Hugging Face libraries off the hub.
    for switch in ("HF_HUB_OFFLINE", "TRANSFORMERS_OFFLINE", "HF_DATASETS_OFFLINE"):
        os.environ[switch] = "1"
    if name == "llamacpp":
        from ..models import resolve_gguf
        from ..prefix_cache import open_store
        from .llamacpp import LlamaCppBackend

        return LlamaCppBackend(resolve_gguf(model), n_ctx=n_ctx, threads=threads, n_gpu_layers=n_gpu_layers, seed=seed,
                               prefix_store=open_store(prefix_cache))
    if name == "transformers":
        from .transformers import TransformersBackend

        return TransformersBackend(model, n_ctx=n_ctx, threads=threads, n_gpu_layers=n_gpu_layers, seed=seed)
    raise UserError(f"unknown backend {name!r}; choose one of {', '.join(BACKENDS)}")


def model_location(name: str, model: str | None) -> Path:
    """The file (or checkpoint folder) a backend would load for ``--model``, found without loading it."""
    from ..models import resolve_gguf

    if name == "transformers" and model is not None and model not in EMBEDDED and Path(model).expanduser().is_dir():
        return Path(model).expanduser()
    return resolve_gguf(model)
