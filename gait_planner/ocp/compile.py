"""Compile CasADi Functions to C shared libraries, cached on disk by their source.

A Function is generated as C (`Function.generate`) and built with the system C compiler
(`cc -O1 -shared -fPIC`) into the cache folder, `$GAIT_PLANNER_CACHE` or
`~/.cache/gait_planner`, named by the SHA-256 of its `Source.key` (what it is, known before
it is formed: e.g. the serialisation of the Function it is derived from), the flags and
CasADi's version. Libraries already built are loaded straight away, without forming their
Functions (walker3d's element derivatives take 2 s to form and generate), so a problem is
compiled once per machine; the libraries missing are built in parallel, one compiler
process per core, the largest first. A library is written under a temporary name
and renamed when complete, so an interrupted build never leaves a half-written one.
The compiler is needed only for libraries not yet in the cache: a cache filled elsewhere
(`make setup`) serves a machine without one. Before building, `compile_sources` tells its
`notify` callback what it builds and how long the last build in this cache folder took
(`LAST_BUILD`).
-O1: walker3d's dynamics Hessian element (5 MB of C) builds in about 30 s and evaluates
six times faster than in CasADi's virtual machine; -O0 builds in 9 s but gains only 2x.
(-Os and -O2 evaluate it in the same time, 2026-11-23.)

A Source with lanes > 1 is a map over that many columns of one SX Function; its C code is
rewritten into one pass of vector operations (`ocp.vectorize`, bit for bit the loop's
results) and built with `vector_flags()` (AVX2 where the CPU has it). Code the rewriter
does not know is built as CasADi's loop.
"""

from __future__ import annotations

import functools
import hashlib
import os
import re
import shutil
import subprocess
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import casadi as ca

from gait_planner.ocp import vectorize

FLAGS = ("-O1", "-shared", "-fPIC")
LAST_BUILD = "last_build.txt"  # in the cache folder: "<libraries> <seconds>" of the last build


class CompileError(RuntimeError):
    """No C compiler, or it failed."""


def cache_folder() -> Path:
    return Path(os.environ.get("GAIT_PLANNER_CACHE", Path.home() / ".cache" / "gait_planner"))


@dataclass(frozen=True)
class Source:
    """A Function to compile: `make` forms it, `key` identifies it (the same key, the same
    Function), so that a library built for the key is loaded without calling `make`."""

    name: str  # the Function's name (a C identifier)
    key: str
    make: Callable[[], ca.Function]
    lanes: int = 1  # > 1: make() is fn.map(lanes), built as one vector pass
    # if set: a Function of more operations than this is not compiled but returned as
    # formed, for CasADi's virtual machine (`ocp.derivatives.INTERPRETED_ABOVE`)
    interpret_above: int | None = None

    @classmethod
    def formed(cls, fn: ca.Function) -> Source:
        """A Function already formed, identified by its serialisation."""
        return cls(fn.name(), fn.serialize(), lambda: fn)


@functools.cache
def vector_flags() -> tuple[str, ...]:
    """FLAGS of the vectorised code: no fused multiply-adds (each lane must round as the
    scalar code does), no notes on the ABI of vector arguments (the vectors never cross
    the library's interface), and AVX2 if /proc/cpuinfo lists it (4 doubles a register;
    without it GCC uses pairs of SSE2 registers)."""
    try:
        cpu = Path("/proc/cpuinfo").read_text()
    except OSError:
        cpu = ""
    avx2 = re.search(r"^flags\s*:.*\bavx2\b", cpu, re.M) is not None
    return FLAGS + ("-ffp-contract=off", "-Wno-psabi") + (("-mavx2",) if avx2 else ())


def _flags(src: Source) -> tuple[str, ...]:
    return vector_flags() if src.lanes > 1 else FLAGS


@functools.cache
def _rewriter_source() -> str:
    return Path(vectorize.__file__).read_text()


def _identity(src: Source) -> bytes:
    """What a library is built from: the Source's key, the flags, CasADi's version and,
    for vector code, the rewriter's own source."""
    parts = [src.key, " ".join(_flags(src)), ca.__version__]
    if src.lanes > 1:
        parts.append(_rewriter_source())
    if src.interpret_above is not None:
        parts.append(f"interpreted above {src.interpret_above} operations")
    return "\n".join(parts).encode()


def compiler() -> str | None:
    """The C compiler's path ($CC or cc), or None if there is none."""
    return shutil.which(os.environ.get("CC", "cc"))


def compile_functions(functions: list[ca.Function], folder: Path | None = None) -> list[ca.Function]:
    """The compiled (external) equivalents of `functions`, in order, each identified by its
    serialisation. Raises CompileError (see `compile_sources`)."""
    return compile_sources([Source.formed(fn) for fn in functions], folder)


def compile_sources(sources: list[Source], folder: Path | None = None,
                    notify: Callable[[str], None] | None = None) -> list[ca.Function]:
    """The compiled (external) Functions of `sources`, in order, or, for a Source whose
    Function has more operations than its `interpret_above`, that Function as formed (no
    library is built for it, so it is formed at every call). A Source whose library is
    cached is not formed. notify: called once, before a build (not when all is cached),
    with what is built and how long the last build took. Raises CompileError (no compiler
    for a library not in the cache, a failed build, a cache folder that cannot be
    written)."""
    folder = cache_folder() if folder is None else folder
    try:
        return _compile(sources, folder, notify or (lambda text: None))
    except OSError as err:
        raise CompileError(f"cannot build in {folder}: {err}") from None


def last_build(folder: Path | None = None) -> tuple[int, float] | None:
    """(libraries, seconds) of the last build in the cache folder, None if unknown."""
    try:
        count, seconds = (Path(folder or cache_folder()) / LAST_BUILD).read_text().split()
        return int(count), float(seconds)
    except (OSError, ValueError):
        return None


def _announce(count: int, folder: Path) -> str:
    last = last_build(folder)
    before = (f"the last build here took {last[1]:.0f} s for {last[0]} libraries" if last
              else "roughly a minute for walker2d or walker3d on 2 cores")
    return (f"compiling up to {count} derivative element{'s' if count > 1 else ''} to C into "
            f"{folder} (once per machine and problem; {before})")


def _compile(sources: list[Source], folder: Path,
             notify: Callable[[str], None]) -> list[ca.Function]:
    folder.mkdir(parents=True, exist_ok=True)
    libraries: list[Path | ca.Function] = []
    jobs: list[tuple[Path, Path, tuple[str, ...]]] = []
    with tempfile.TemporaryDirectory(dir=folder) as work:
        for src in sources:
            library = _library(src, folder)
            if library.exists() or library in (job[0] for job in jobs):
                libraries.append(library)
                continue
            function = src.make()
            if src.interpret_above is not None and function.n_instructions() > src.interpret_above:
                libraries.append(function)
                continue
            libraries.append(library)
            if not jobs:  # the first library to build
                if compiler() is None:
                    raise CompileError(
                        f"no C compiler found ({os.environ.get('CC', 'cc')!r}: set CC, or "
                        f"install gcc) to build what the cache {folder} lacks "
                        f"({library.name}, ...)")
                missing = {_library(s, folder) for s in sources} - {
                    lib for lib in libraries if isinstance(lib, Path) and lib.exists()}
                notify(_announce(len(missing), folder))
                start = time.perf_counter()
            source = Path(work) / f"{src.name}.c"
            generator = ca.CodeGenerator(source.name, {"with_header": False})
            generator.add(function)
            generator.generate(f"{work}{os.sep}")
            if src.lanes > 1:
                try:
                    source.write_text(vectorize.vectorize_map(source.read_text(), src.lanes))
                except vectorize.Unsupported:
                    pass  # CasADi's loop, as generated
            jobs.append((library, source, _flags(src)))
        if jobs:
            _build_all(compiler(), jobs, work)
            (folder / LAST_BUILD).write_text(f"{len(jobs)} {time.perf_counter() - start:.1f}\n")
    return [lib if isinstance(lib, ca.Function) else ca.external(src.name, str(lib))
            for src, lib in zip(sources, libraries)]


def _library(src: Source, folder: Path) -> Path:
    return folder / f"{src.name}_{hashlib.sha256(_identity(src)).hexdigest()[:16]}.so"


def _build_all(compiler: str, jobs: list[tuple[Path, Path, tuple[str, ...]]], work: str) -> None:
    """Build (library, source, flags) jobs, one compiler per usable core, the largest source
    first; a core takes the next job as soon as its own is done. After a failure no new job
    starts, and the first failure is raised. (Waiting for the jobs in the order they
    started left a core idle behind the largest one: G1's 45 elements, 35 MB of C, took
    174 s to build on 2 cores, 1.15 cores busy on average; 2026-11-29, HISTORY.)"""
    failed = threading.Event()

    def build(job: tuple[Path, Path, tuple[str, ...]]) -> str | None:
        library, source, flags = job
        if failed.is_set():
            return None
        partial = Path(work) / (library.name + ".partial")
        done = subprocess.run([compiler, *flags, str(source), "-o", str(partial), "-lm"],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if done.returncode != 0:
            failed.set()
            return f"{compiler} failed on {library.stem}: {done.stdout.strip()[-500:]}"
        os.replace(partial, library)
        return None

    largest_first = sorted(jobs, key=lambda job: job[1].stat().st_size, reverse=True)
    with ThreadPoolExecutor(max_workers=_cores()) as pool:
        errors = [error for error in pool.map(build, largest_first) if error]
    if errors:
        raise CompileError(errors[0])


def _cores() -> int:
    """The cores this process may run on (its affinity where the OS tells it)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1
