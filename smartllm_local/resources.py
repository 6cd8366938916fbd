"""Where the project's data folders (benchmark/, domains/, prompts/) live.

In a source checkout or an editable install they sit beside the package; a
wheel carries them inside the package as ``_data/``.
"""

from __future__ import annotations

from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parent


def data_dir(name: str) -> Path:
    """Return the folder ``name`` ("benchmark", "domains" or "prompts"), wherever it was installed."""
    for candidate in (_PACKAGE_DIR / "_data" / name, _PACKAGE_DIR.parent / name):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(
        f"the project's {name}/ folder is missing next to {_PACKAGE_DIR}; reinstall smartllm-local"
    )
