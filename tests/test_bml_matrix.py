"""Every behaviour element of docs/bml.md on X Bot, the Ready Player Me avatar and SmartBody's Brad
(``benchmarks/bml_matrix.py``): each cell is realized, measured on the written motion against the same
scene without the behaviour, or warns for a stated reason; none does nothing silently, and the table in
docs/bml.md says what the matrix measures."""
from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

from corpus_data import require_corpus

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import bml_matrix  # noqa: E402

pytest.importorskip("infuse_manipulation")
pytest.importorskip("infuse_reach")


@pytest.fixture(scope="module")
def cells():
    require_corpus()
    return bml_matrix.run(verbose=False)


def test_every_cell_is_realized_or_warns_for_a_reason(cells):
    assert len(cells) == len(bml_matrix.ROWS) * len(bml_matrix.CAST)
    failed = [f"{c.row} on {c.character}: {c.text()}" for c in cells if c.status == "fails"]
    assert not failed, failed
    assert all(c.warning for c in cells if c.status == "warns")


def test_the_rows_are_the_elements_docs_bml_lists():
    """Every element of the Elements table has a row (its aliases aside), and BML 1.0's core ones all."""
    text = bml_matrix.DOCS.read_text(encoding="utf-8")
    elements = text.split("## Elements", 1)[1].split("\n## ", 1)[0]
    listed = {m for line in elements.splitlines() if line.startswith("| `")
              for m in re.findall(r"`<?([A-Za-z:]+)", line.split("|")[1].split("(")[0])}
    rows = " ".join(r.body + " " + r.name for r in bml_matrix.ROWS)
    aliases = {"reach", "grab", "sbm:event", "sbm:grab", "sbm:reach", "bml"}
    missing = [e for e in listed - aliases if f"<{e} " not in rows and e not in rows]
    assert not missing, missing
    core = ("speech", "gaze", "gazeShift", "head", "headDirectionShift", "faceLexeme", "faceFacs", "faceShift", "gesture",
            "pointing", "posture", "postureShift", "locomotion", "wait")
    assert all(any(r.body.startswith(f"<{e} ") for r in bml_matrix.ROWS) for e in core)


def test_the_docs_table_says_what_the_matrix_measures(cells):
    """docs/bml.md's generated table has a cell per behaviour and character, realized or warning as
    measured now, with the same warning (the figures may move a little as controllers change)."""
    text = bml_matrix.DOCS.read_text(encoding="utf-8")
    table = text.split(bml_matrix.BEGIN, 1)[1].split(bml_matrix.END, 1)[0].strip().splitlines()[2:]
    documented = {}
    for line in table:
        parts = [p.strip() for p in line.strip("|").split(" | ")]
        for cast, cell in zip(bml_matrix.CAST, parts[2:]):
            documented[(parts[0], cast.key)] = cell
    for cell in cells:
        shown = documented.get((cell.row, cell.character))
        assert shown is not None, f"{cell.row} on {cell.character} is not in docs/bml.md: run the benchmark with --write-docs"
        assert shown.split(":", 1)[0] == cell.text().split(":", 1)[0], (cell.row, cell.character, shown, cell.text())
        assert not cell.warning or cell.warning.replace("|", "/") in shown, (cell.row, cell.character, shown, cell.warning)
