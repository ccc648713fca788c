"""The compiler jobs of `ocp.compile._build_all`: the largest source first, a failure named."""

from __future__ import annotations

import os
import stat

import pytest

from gait_planner.ocp import compile as compile_module
from gait_planner.ocp.compile import CompileError, FLAGS, compiler


def _jobs(tmp_path, sizes: dict[str, int], broken: str | None = None):
    jobs = []
    for name, size in sizes.items():
        source = tmp_path / f"{name}.c"
        body = "this is not C;" if name == broken else f"double {name}(double x) {{ return x; }}"
        source.write_text(body + "\n" + "/*" + "x" * size + "*/\n")
        jobs.append((tmp_path / f"{name}.so", source, FLAGS))
    return jobs


def _logging_compiler(tmp_path):
    """A compiler that writes the source it is given to a log, then runs cc."""
    log = tmp_path / "started.log"
    script = tmp_path / "cc-logged"
    script.write_text(f"#!/bin/sh\nfor a in \"$@\"; do case $a in *.c) echo $a >> {log};; esac; "
                      f"done\nexec {compiler()} \"$@\"\n")
    script.chmod(script.stat().st_mode | stat.S_IEXEC)
    return str(script), log


@pytest.mark.skipif(compiler() is None, reason="no C compiler")
def test_the_largest_source_is_built_first(tmp_path, monkeypatch):
    monkeypatch.setattr(compile_module, "_cores", lambda: 1)
    script, log = _logging_compiler(tmp_path)
    jobs = _jobs(tmp_path, {"small": 10, "large": 5000, "middle": 500})
    compile_module._build_all(script, jobs, str(tmp_path))
    started = [os.path.basename(line) for line in log.read_text().split()]
    assert started == ["large.c", "middle.c", "small.c"]
    assert all(library.exists() for library, _, _ in jobs)


@pytest.mark.skipif(compiler() is None, reason="no C compiler")
def test_a_failed_source_is_named_and_stops_the_jobs_not_started(tmp_path, monkeypatch):
    monkeypatch.setattr(compile_module, "_cores", lambda: 1)
    script, log = _logging_compiler(tmp_path)
    jobs = _jobs(tmp_path, {"fine": 5000, "broken": 500, "never": 10}, broken="broken")
    with pytest.raises(CompileError, match="failed on broken"):
        compile_module._build_all(script, jobs, str(tmp_path))
    started = [os.path.basename(line) for line in log.read_text().split()]
    assert started == ["fine.c", "broken.c"]
    assert (tmp_path / "fine.so").exists() and not (tmp_path / "broken.so").exists()
