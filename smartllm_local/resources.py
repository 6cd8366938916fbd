"""Where the project's data folder (domains/) lives.

In a source checkout or an editable install it sits beside the package; a
wheel carries it inside the package as ``_data/``.
"""

from __future__ import annotations

from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parent


def data_dir(name: str) -> Path:
    """Return the data folder ``name`` ("domains"), wherever it was installed."""
    for candidate in (_PACKAGE_DIR / "_data" / name, _PACKAGE_DIR.parent / name):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(
        f"the project's {name}/ folder is missing next to {_PACKAGE_DIR}; reinstall smartllm-local"
    )
