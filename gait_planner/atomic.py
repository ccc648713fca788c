"""Atomic file output: a file appears complete under its name, or not at all.

`atomic_target` writes to a temporary file ``.<name>.<pid>.<12 hex digits>.tmp`` beside the
target and renames it over the target when complete. A process killed while writing
(SIGKILL, power loss) leaves that temporary file behind, never a partial target;
`remove_stale_temporaries` removes such leftovers of processes that no longer run.
"""

from __future__ import annotations

import contextlib
import os
import re
import secrets
from pathlib import Path
from typing import Iterator

__all__ = ["atomic_target", "remove_stale_temporaries"]

_TEMPORARY = re.compile(r"\..+\.(?P<pid>[0-9]{1,9})\.[0-9a-f]{12}\.tmp")


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


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def remove_stale_temporaries(folder: str | os.PathLike) -> list[Path]:
    """Remove from `folder` (not its subfolders) the temporary files of `atomic_target`
    whose writing process no longer runs (killed while writing); return their paths.

    Only regular files named exactly as `atomic_target` names them are considered; those
    of running processes (another writer at work) stay, and so does everything else. A
    folder that does not exist holds nothing to remove. A recycled process id keeps its
    leftover until that process ends too.
    """
    directory = Path(folder)
    if not directory.is_dir():
        return []
    removed = []
    for path in sorted(directory.iterdir()):
        match = _TEMPORARY.fullmatch(path.name)
        if not match or path.is_symlink() or not path.is_file():
            continue
        if _running(int(match["pid"])):
            continue
        with contextlib.suppress(FileNotFoundError):  # removed meanwhile by another process
            path.unlink()
            removed.append(path)
    return removed
