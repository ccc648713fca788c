"""A gait library's folder: its manifest and its index."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gait_planner.gaitlib.index import (LibraryError, LibraryIndex, Manifest, PlanRow,
                                        load_start, read_manifest, save_start, start_path,
                                        write_manifest)
from gait_planner.ocp.warm_starts import StoredPlan

MANIFEST = Manifest(scene="walker2d", gait="", grid="step_length=0.5/0.6", request={})


def _row(name: str, **changes) -> PlanRow:
    row = PlanRow(name=name, request={"step_length": 0.5}, status="ok", reason="", cost=1.5,
                  duration=0.5, sigma=[1.0, 1.5], iterations=7, solve_time=0.1,
                  certificate="OK", checks="pass", start="cold", attempts=1,
                  mcap=f"{name}.mcap")
    return dataclasses.replace(row, **changes)


def test_rows_are_kept_once_and_read_back_as_written(tmp_path):
    write_manifest(tmp_path, MANIFEST)
    index = LibraryIndex(tmp_path)
    assert index.add(_row("p00")) and index.add(_row("p01", status="failed", cost=None))
    assert not index.add(_row("p00", cost=99.0))  # a finished point stays as it was
    index.close()
    again = LibraryIndex(tmp_path)
    assert again.rows() == [_row("p00"), _row("p01", status="failed", cost=None)]
    assert again.names() == {"p00", "p01"}
    again.close()


def test_a_folder_of_another_library_is_refused_naming_what_differs(tmp_path):
    write_manifest(tmp_path, MANIFEST)
    write_manifest(tmp_path, MANIFEST)  # the same library: resumed
    assert read_manifest(tmp_path) == MANIFEST
    with pytest.raises(LibraryError, match="grid 'step_length=0.5/0.6' there"):
        write_manifest(tmp_path, dataclasses.replace(MANIFEST, grid="step_length=0.7"))
    with pytest.raises(LibraryError, match="not a gait library"):
        read_manifest(tmp_path / "elsewhere")


def test_an_optimum_is_read_back_bit_for_bit(tmp_path):
    rng = np.random.default_rng(0)
    plan = StoredPlan(0.6, 0.8, rng.normal(size=5), rng.normal(size=5), rng.normal(size=3),
                      rng.normal(size=(2, 4)))
    (tmp_path / "plans").mkdir()
    save_start(start_path(tmp_path, "p00"), plan)
    back = load_start(start_path(tmp_path, "p00"))
    assert (back.step, back.mu) == (0.6, 0.8)
    for name in ("x", "lam_x", "lam_g", "qref"):
        assert np.array_equal(getattr(back, name), getattr(plan, name))


def test_a_cluster_address_nobody_answers_is_refused_before_the_folder_is_made(tmp_path):
    from gait_planner.gaitlib.build import build_library

    with pytest.raises(LibraryError, match="no Ray cluster answers at 127.0.0.1:1"):
        build_library(tmp_path / "lib", MANIFEST, address="127.0.0.1:1")
    assert not (tmp_path / "lib").exists()
