"""The README and docs/ against what `tools/docs.py` renders from the stored JSON (no
solving): a generated number that differs from its source, a README over 200 lines or a
link to a missing file fails here."""

from __future__ import annotations

import importlib.util
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINK = re.compile(r"\]\(([^)\s]+)\)")


@pytest.fixture(scope="module")
def docs():
    spec = importlib.util.spec_from_file_location("docs_tool", ROOT / "tools" / "docs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_generated_region_matches_its_json(docs):
    assert docs.stale() == [], "run `make docs` (or `.venv/bin/python tools/docs.py`)"


def test_every_page_has_regions_and_every_region_a_renderer(docs):
    for page in docs.PAGES:
        names = [m.group(2) for m in docs.REGION.finditer((ROOT / page).read_text())]
        assert names, f"{page} has no generated region"
        assert set(names) <= set(docs.RENDER), page
    assert set(docs.COMMANDS) <= {p.stem for p in docs.RESULTS.glob("*.json")}, (
        "a JSON file named in COMMANDS is missing from benchmarks/results/")


def test_a_changed_number_makes_its_region_stale(docs, monkeypatch):
    original = docs.load

    def altered(name: str) -> dict:
        data = original(name)
        if name == "default_plan":
            data["summary"]["cost_value"] += 0.001
        return data

    monkeypatch.setattr(docs, "load", altered)
    assert {"README.md: docs:plan_line", "docs/results.md: docs:default_plan",
            "docs/results.md: docs:posture"} <= set(docs.stale())


def test_an_unmeasured_time_renders_as_a_todo(docs, monkeypatch):
    original = docs.load
    measured = json.loads((ROOT / "docs" / "measured.json").read_text())
    rows = measured["rows"]

    def with_test(time):
        return {**measured, "rows": {**rows, "make_test": {**rows["make_test"], "time": time}}}
    monkeypatch.setattr(docs, "load", lambda name: (
        with_test(None) if name == "measured" else original(name)))
    assert "not measured yet (`time make test` once prepared)" in docs.render_measured()
    monkeypatch.setattr(docs, "load", lambda name: (
        with_test("5 min") if name == "measured" else original(name)))
    assert "| `make test` (every test not marked slow) | 5 min |" in docs.render_measured()


def test_the_readme_table_holds_docs_measured_json():
    """Each row of docs/measured.json is a row of the README's table, its time as stored;
    its date stands in the line under the table."""
    measured = json.loads((ROOT / "docs" / "measured.json").read_text())
    block = (ROOT / "README.md").read_text().split("<!-- docs:measured -->")[1].split(
        "<!-- /docs:measured -->")[0]
    table_rows = [line for line in block.splitlines() if line.startswith("| ")]
    assert len(table_rows) == 1 + len(measured["rows"])  # the head and one row each
    for row in measured["rows"].values():
        assert f"| {row['command']} | {row['time']} |" in table_rows, row["command"]
        assert row["date"] in block.splitlines()[-1], row["date"]


def test_readme_is_short():
    lines = (ROOT / "README.md").read_text().count("\n")
    assert lines <= 200, f"README.md has {lines} lines; the limit is 200 (move detail to docs/)"


@pytest.mark.parametrize("page", ["README.md", "docs/user-guide.md", "docs/results.md",
                                  "docs/design.md"])
def test_links_point_to_existing_files(page):
    path = ROOT / page
    if not path.is_file():
        pytest.skip(f"{page} is not written yet")
    missing = []
    for target in LINK.findall(path.read_text()):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue  # a web address or an anchor on the same page
        if not (path.parent / target.split("#")[0]).exists():
            missing.append(target)
    assert missing == [], f"{page} links to missing files: {missing}"
