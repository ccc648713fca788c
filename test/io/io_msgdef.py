"""A tiny independent .msg/.srv reader for the io tests: field names and types only."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
MSG_DEFS = REPO / "msg_defs"


def fields(text: str) -> dict[str, str]:
    """name -> type of the fields (constants skipped) of one .msg text."""
    out = {}
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        type_, name = line.split()[:2]
        if "=" in line.split(None, 2)[1] or "=" in name:
            continue  # a constant
        out[name] = type_
    return out


def msg_fields(name: str) -> dict[str, str]:
    return fields((MSG_DEFS / "msg" / f"{name}.msg").read_text())


def srv_response_fields(name: str) -> dict[str, str]:
    text = (MSG_DEFS / "srv" / f"{name}.srv").read_text()
    return fields(text.split("\n---", 1)[1])


def share_msg_text(package: str, name: str) -> str | None:
    """The installed .msg text of a standard type from <venv>/share, if present."""
    import sys

    path = Path(sys.prefix) / "share" / package / "msg" / f"{name}.msg"
    return path.read_text() if path.is_file() else None
