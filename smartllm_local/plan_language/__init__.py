"""The plan language: SMART-LLM's Pythonic plans, parsed into data and never executed as code."""

from __future__ import annotations

from pathlib import Path

from ..errors import UserError
from .ir import Call, Form, Function, Join, NewThread, Plan, SkillCall, Sleep, Start
from .parse import parse_plan

__all__ = [
    "Call", "Form", "Function", "Join", "NewThread", "Plan", "SkillCall", "Sleep", "Start",
    "parse_plan", "read_plan",
]


def read_plan(path: str | Path, **kwargs) -> Plan:
    """Read a plan file and parse it (keyword arguments as for :func:`parse_plan`)."""
    path = Path(path)
    try:
        source = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise UserError(f"cannot read plan {path}: {exc.strerror or exc}") from exc
    except UnicodeDecodeError as exc:
        raise UserError(f"plan {path} is not UTF-8 text ({exc.reason})") from exc
    return parse_plan(source, name=str(path), **kwargs)
