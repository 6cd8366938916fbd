"""What produced a run's numbers: the model file's digest, the versions, the task files.

A benchmark run's ``run.json`` holds this beside every argument, so a table can
be traced to exactly what made it, and a run directory cannot be resumed with
anything else. Digesting a 40 GB GGUF file takes minutes: digests are kept in
the user's cache, keyed by the file's path, size and modification time.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterable, Mapping, Sequence
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path
from typing import Any

from .files import read_cache_map, remember_in_cache_map
from .world.scenes import cache_root

PACKAGES = ("smartllm-local", "llama-cpp-python", "ai2thor", "transformers", "torch")
_CHUNK = 1 << 20


def sha256_file(path: str | Path, cache: Path | None = None) -> str:
    """The file's sha256 (hex), from the cache when the file has not changed since it was digested."""
    path = Path(path).resolve()
    known = _known_digests(cache)
    digest = known.get(_digest_key(path))
    if isinstance(digest, str) and len(digest) == 64:
        return digest
    hasher = hashlib.sha256()
    with open(path, "rb") as handle:
        while chunk := handle.read(_CHUNK):
            hasher.update(chunk)
    digest = hasher.hexdigest()
    remember_digest(path, digest, cache)
    return digest


def remember_digest(path: str | Path, digest: str, cache: Path | None = None) -> None:
    """Keep a digest just computed while writing ``path`` (so it is not read again to digest it)."""
    # a read-only cache only costs the next run a digest
    remember_in_cache_map(_digest_store(cache), _digest_key(Path(path).resolve()), digest)


def _digest_store(cache: Path | None) -> Path:
    return (cache or cache_root()) / "digests.json"


def _digest_key(path: Path) -> str:
    stat = path.stat()
    return f"{path}|{stat.st_size}|{stat.st_mtime_ns}"


def _known_digests(cache: Path | None) -> dict[str, Any]:
    return read_cache_map(_digest_store(cache))  # missing or damaged: digest again


def file_record(path: str | Path) -> dict[str, Any]:
    """A file's name, size and sha256."""
    path = Path(path)
    return {"name": path.name, "path": str(path.resolve()), "size": path.stat().st_size, "sha256": sha256_file(path)}


def versions(packages: Iterable[str] = PACKAGES) -> dict[str, str | None]:
    """Installed versions of the packages a result depends on (None: not installed)."""
    found: dict[str, str | None] = {}
    for name in packages:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = None
    return found


def model_record(model: str | os.PathLike[str]) -> dict[str, Any]:
    """The model as run.json records it: a file's digest, or a checkpoint folder's files' digests."""
    path = Path(model)
    if path.is_dir():
        files = sorted(p for p in path.rglob("*") if p.is_file())
        return {"name": path.name, "path": str(path.resolve()), "size": sum(p.stat().st_size for p in files),
                "files": {str(p.relative_to(path)): sha256_file(p) for p in files}}
    return file_record(path)


def folder_digest(folder: str | Path) -> str:
    """One digest of every file under ``folder`` (names and contents)."""
    folder = Path(folder)
    hasher = hashlib.sha256()
    for path in sorted(p for p in folder.rglob("*") if p.is_file()):
        hasher.update(str(path.relative_to(folder)).encode() + b"\0" + sha256_file(path).encode())
    return hasher.hexdigest()


def run_manifest(arguments: Mapping[str, Any], model: Path | None, settings: Mapping[str, Any],
                 task_files: Sequence[Path], catalogue: Path, prompts: Path,
                 split: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """``run.json``: what a run is (``identity``: a run folder is resumed only by the same) and when;
    ``model`` None: a method that uses no model; ``split``: the benchmark's development/test split, kept for
    the report where the run's tasks are a domain's own (beside the identity: ``--split`` is an argument, and
    a split that grows by a task when the task files do leaves nothing else to compare)."""
    described = model_record(model) if model is not None else {"path": None}
    identity = {
        # as run.json holds them (a tuple reads back as a list), so that the same arguments compare equal
        "arguments": json.loads(json.dumps(dict(arguments), default=str)),
        "model": {k: described[k] for k in ("name", "size", "sha256", "files") if k in described},
        "settings": dict(settings),
        "versions": versions(),
        "task_files": {str(Path(p).resolve()): sha256_file(p) for p in task_files},
        "catalogue": {str(Path(catalogue).resolve()): sha256_file(catalogue)},
        "prompts": folder_digest(prompts),
    }
    manifest = {"identity": identity, "model_path": described["path"],
                "started": datetime.now(timezone.utc).isoformat(timespec="seconds")}
    if split is not None:
        manifest["split"] = dict(split)
    return manifest
