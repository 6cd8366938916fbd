"""The viewer page: the template shipped with the package, its script and style inlined, and the run's
data embedded, so that one HTML file opens from disk on a machine with no network and no server."""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path
from typing import Any

from ...files import check_output_file, write_atomic
from .data import load_view

DEFAULT_NAME = "viewer.html"


def _asset(name: str) -> str:
    return resources.files(__package__).joinpath("assets", name).read_text(encoding="utf-8")


def embed(data: Any) -> str:
    """The data as JSON that cannot end the script element holding it (every ``<`` escaped, which JSON allows
    inside strings, the only place one can be)."""
    return json.dumps(data, separators=(",", ":")).replace("<", "\\u003c")


def render_page(data: dict[str, Any]) -> str:
    """The page for ``data`` (what :func:`~.data.load_view` reads)."""
    title = f"{data['label']} · smartllm-local run viewer"
    return (_asset("viewer.html")
            .replace("{{title}}", _escape(title))
            .replace("{{style}}", _asset("viewer.css"))
            .replace("{{script}}", _asset("viewer.js"))
            .replace("{{data}}", embed(data)))


def write_viewer(folder: str | Path, out: str | Path | None = None) -> Path:
    """Read the run in ``folder`` and write its page to ``out`` (default ``FOLDER/viewer.html``), atomically.

    Raises:
        UserError: ``folder`` holds no run (see :func:`~.data.load_view`), or ``out`` cannot be written.
    """
    target = Path(out) if out is not None else Path(folder) / DEFAULT_NAME
    check_output_file(target, "--out")
    return write_atomic(target, render_page(load_view(folder)))


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")
