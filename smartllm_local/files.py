"""Writing result files so that a crash or a Ctrl-C never leaves half of one behind."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any

from .errors import UserError


def check_output_file(path: str | Path, what: str = "output file") -> Path:
    """Fail early, before any work is done, when ``path`` can never be written as a file:
    it is an existing folder, or one of its parents is an existing file."""
    path = Path(path)
    if path.is_dir():
        raise UserError(f"{what} {path} is an existing folder: give a file name, e.g. {path / 'out.json'}")
    _check_parents(path, what)
    return path


def check_output_folder(path: str | Path, what: str = "output folder") -> Path:
    """Fail early, before any work is done, when ``path`` can never be used as a folder:
    it is an existing file, or one of its parents is."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise UserError(f"{what} {path} is an existing file: give a folder (it is created if missing)")
    _check_parents(path, what)
    return path


def _check_parents(path: Path, what: str) -> None:
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise UserError(f"cannot write {what} {path}: {parent} is a file, not a folder")
            return


def write_atomic(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file in the same folder, then rename it.

    Raises:
        UserError: when the folder cannot be made or the file cannot be written or replaced
            (``path`` is a folder, no permission, disk full); nothing is left behind.
    """
    path = Path(path)
    if path.is_dir():
        raise UserError(f"cannot write {path}: it is a folder; give a file name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    except OSError as exc:
        raise UserError(f"cannot write {path}: {exc.strerror or exc}") from exc
    try:
        os.fchmod(fd, _mode_for(path))
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError):
            reason = "it is a folder; give a file name" if isinstance(exc, IsADirectoryError) else exc.strerror or exc
            raise UserError(f"cannot write {path}: {reason}") from exc
        raise
    return path


def _mode_for(path: Path) -> int:
    """The permissions a plain ``open(path, "w")`` would give, not mkstemp's owner-only 0600:
    an existing file keeps its own, a new one gets 0666 less the umask."""
    try:
        return path.stat().st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def json_text(data: Any) -> str:
    """JSON as every result file holds it: indented, ending with a newline."""
    return json.dumps(data, indent=2) + "\n"


def write_json(path: str | Path, data: Any) -> Path:
    return write_atomic(path, json_text(data))


def read_json(path: str | Path, what: str) -> Any:
    """Read a JSON file the user named; problems become a UserError naming the file."""
    path = Path(path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UserError(f"cannot read {what} {path}: {exc.strerror or exc}") from exc
    except ValueError as exc:
        raise UserError(f"{what} {path} is not valid JSON: {exc}") from exc
