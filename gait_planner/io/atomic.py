"""Atomic file output: a file appears complete under its name, or not at all."""

from __future__ import annotations

import contextlib
import os
import secrets
from pathlib import Path
from typing import Iterator


@contextlib.contextmanager
def atomic_target(target: Path) -> Iterator[Path]:
    """Yield a fresh temporary path beside `target` to write to; on success it is renamed
    to `target` (so readers never see a half-written file), on any error it is removed.
    The temporary file is created empty (O_EXCL: never reused; mode 0666 minus the
    process umask, like open()). Raises OSError if the writer left it empty."""
    tmp = target.with_name(f".{target.name}.{os.getpid()}.{secrets.token_hex(6)}.tmp")
    os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
    try:
        yield tmp
        if tmp.stat().st_size == 0:
            raise OSError(f"nothing was written to {tmp}")
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
