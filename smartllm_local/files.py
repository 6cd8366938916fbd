"""Writing result files so that a crash or a Ctrl-C never leaves half of one behind."""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .errors import UserError


def check_output_file(path: str | Path, what: str = "output file") -> Path:
    """Fail early, before any work is done, when ``path`` can never be written as a file:
    it is an existing folder, one of its parents is an existing file, or nothing can be made in its nearest
    parent that exists."""
    path = Path(path)
    if path.is_dir():
        raise UserError(f"{what} {path} is an existing folder: give a file name, e.g. {path / 'out.json'}")
    _check_parents(path, what)
    return path


def check_output_folder(path: str | Path, what: str = "output folder") -> Path:
    """Fail early, before any work is done, when ``path`` can never be used as a folder:
    it is an existing file, one of its parents is, or nothing can be made in it or in its nearest parent
    that exists (read-only, no permission: a plan of minutes was written, then lost)."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise UserError(f"{what} {path} is an existing file: give a folder (it is created if missing)")
    _check_parents(path, what, folder=True)
    return path


def _check_parents(path: Path, what: str, *, folder: bool = False) -> None:
    for parent in [path, *path.parents] if folder else path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise UserError(f"cannot write {what} {path}: {parent} is a file, not a folder")
            try:  # a folder made and taken away again: writing there works, whoever runs this
                os.rmdir(tempfile.mkdtemp(prefix=".check-", dir=parent))
            except OSError as exc:
                raise UserError(f"cannot write {what} {path}: nothing can be made in {parent} "
                                f"({exc.strerror or exc}); give a folder you can write to") from exc
            return


def write_atomic(path: str | Path, data: str | bytes | Sequence[bytes]) -> Path:
    """Write ``data`` (text as UTF-8, bytes, or bytes in parts) to ``path`` through a temporary file in the same
    folder, then rename it.

    The temporary file is made as ``open(path, "w")`` would make the file (0666 less the umask, which the kernel
    applies); a file that exists keeps its own permissions.

    Raises:
        UserError: when the folder cannot be made or the file cannot be written or replaced
            (``path`` is a folder, no permission, disk full); nothing is left behind.
    """
    path = Path(path)
    if path.is_dir():
        raise UserError(f"cannot write {path}: it is a folder; give a file name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = _new_file(path)
    except OSError as exc:
        raise UserError(f"cannot write {path}: {exc.strerror or exc}") from exc
    try:
        with contextlib.suppress(OSError):
            os.fchmod(fd, path.stat().st_mode & 0o7777)
        parts = [data.encode("utf-8")] if isinstance(data, str) else [data] if isinstance(data, bytes) else data
        with os.fdopen(fd, "wb") as handle:
            for part in parts:
                handle.write(part)
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(exc, OSError):
            reason = "it is a folder; give a file name" if isinstance(exc, IsADirectoryError) else exc.strerror or exc
            raise UserError(f"cannot write {path}: {reason}") from exc
        raise
    return path


def _new_file(path: Path) -> tuple[int, Path]:
    """A new file beside ``path`` with a name of its own, open for writing."""
    while True:
        tmp = path.with_name(f".{path.name}.{secrets.token_hex(6)}")
        try:
            return os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), tmp
        except FileExistsError:
            continue


def json_text(data: Any) -> str:
    """JSON as every result file holds it: indented, ending with a newline."""
    return json.dumps(data, indent=2) + "\n"


def write_json(path: str | Path, data: Any) -> Path:
    return write_atomic(path, json_text(data))


def read_cache_map(path: str | Path) -> dict[str, Any]:
    """A JSON object this project keeps in its cache; empty where it is missing or damaged (never trusted then:
    what it would have said is found again)."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def remember_in_cache_map(path: str | Path, key: str, value: Any) -> bool:
    """Add ``key`` to a JSON object kept in the cache (:func:`read_cache_map`), written atomically; whether it
    was written (a cache that cannot be written costs only finding the value again later)."""
    known = read_cache_map(path)
    known[key] = value
    try:
        write_atomic(path, json.dumps(known, indent=1, sort_keys=True) + "\n")
    except UserError:
        return False
    return True


def read_json(path: str | Path, what: str) -> Any:
    """Read a JSON file the user named; problems become a UserError naming the file."""
    path = Path(path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UserError(f"cannot read {what} {path}: {exc.strerror or exc}") from exc
    except ValueError as exc:
        raise UserError(f"{what} {path} is not valid JSON: {exc}") from exc
