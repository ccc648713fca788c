"""Collocation models shared by the tests of this folder, built once per scene and class."""

from __future__ import annotations

from typing import Callable

import pytest

from benchmarks.collocation.minimal import MinimalModel
from benchmarks.collocation.rnea import SpatialModel


def _cached(model, cls) -> Callable[[str], MinimalModel]:
    cache: dict[str, MinimalModel] = {}

    def get(name: str) -> MinimalModel:
        if name not in cache:
            cache[name] = cls(model(name).mb)
        return cache[name]

    return get


@pytest.fixture(scope="module")
def minimal(model) -> Callable[[str], MinimalModel]:
    """minimal(scene name): the scene's `MinimalModel`."""
    return _cached(model, MinimalModel)


@pytest.fixture(scope="module")
def spatial(model) -> Callable[[str], SpatialModel]:
    """spatial(scene name): the scene's `SpatialModel` (recursive Newton-Euler)."""
    return _cached(model, SpatialModel)
