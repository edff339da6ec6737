"""The BVH plugin on every labelled corpus BVH: loading, `infuse info`, round trips and FK."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse.cli.builtin import asset_summary
from infuse.kinematics import end_site_positions, motion_fk

from bvh_reference import matrix_chain_positions, parse_raw
from corpus_data import corpus_file, labels, require_corpus

BVH_LABELS = [doc for doc in labels() if doc["meta"]["format"].startswith("BVH")]
BANDAI = [doc for doc in BVH_LABELS if doc["convention"] == "bandai"]
INFUSE_CLI = Path(sys.executable).with_name("infuse")


def _ids(docs):
    return [doc["file"].rsplit("/", 1)[-1] for doc in docs]


@pytest.fixture(scope="module")
def assets():
    """Every labelled BVH, loaded once: relative path -> Asset."""
    require_corpus()
    return {doc["file"]: infuse.load(corpus_file(doc["file"])) for doc in BVH_LABELS}


def _mapped_names(doc) -> set[str]:
    return {name for name in doc["mapping"].values() if name is not None}


def test_corpus_has_labelled_bvh_files():
    require_corpus()
    assert len(BVH_LABELS) >= 40 and len(BANDAI) >= 30


@pytest.mark.parametrize("doc", BVH_LABELS, ids=_ids(BVH_LABELS))
def test_summary_names_every_mapped_joint(assets, doc):
    asset = assets[doc["file"]]
    summary = asset_summary(asset)
    assert _mapped_names(doc) <= set(summary["joints"])
    assert len(summary["parents"]) == len(summary["joints"]) == doc["joint_count"]
    assert summary["frames"] == doc["meta"]["frames"]
    assert summary["fps"] == pytest.approx(doc["meta"]["fps"], rel=1e-3)
    assert summary["units_detected_by"] == "guess"
    json.dumps(summary)  # the document --json prints


@pytest.mark.parametrize("doc", BVH_LABELS[::12] + BVH_LABELS[-2:], ids=_ids(BVH_LABELS[::12] + BVH_LABELS[-2:]))
def test_cli_info_json(doc):
    path = corpus_file(doc["file"])
    run = subprocess.run([str(INFUSE_CLI), "info", "--json", str(path)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert _mapped_names(doc) <= set(summary["joints"])
    assert summary["format"] == "bvh" and summary["frames"] == doc["meta"]["frames"]
    assert all(-1 <= p < i for i, p in enumerate(summary["parents"]))


def test_units_and_up_axis_are_sensible(assets):
    humanoids = {doc["file"] for doc in BVH_LABELS if doc["humanoid"]}
    assert len(humanoids) >= len(BVH_LABELS) - 1
    for rel in humanoids:
        asset = assets[rel]
        motion = next(iter(asset.motions.values()))
        _, pos = motion_fk(motion)
        body = pos[:, 1:] if rel.startswith("bandai/") else pos  # Bandai's joint_Root stays at the origin
        spread = np.ptp(body, axis=1).mean(axis=0)
        assert spread[1] >= spread[2], rel  # upright: taller along +Y than deep along Z
        assert 0.5 < spread[1] < 3.0, (rel, spread)  # human-sized once in metres (tests/test_bvh_units.py: adult-sized)
    makehuman = assets["rgbdacquisition/Motions/makehuman.bvh"]
    assert makehuman.source_up_axis == "Z" and makehuman.source_units == "dm"


@pytest.mark.parametrize("doc", BVH_LABELS, ids=_ids(BVH_LABELS))
def test_round_trip_keeps_global_positions(assets, doc, tmp_path):
    asset = assets[doc["file"]]
    out = infuse.save(asset, tmp_path / "copy.bvh")
    again = infuse.load(out)
    first, second = next(iter(asset.motions.values())), next(iter(again.motions.values()))
    assert again.skeleton.names == asset.skeleton.names
    assert again.meta["channels"] == asset.meta["channels"]
    assert (again.source_units, again.source_up_axis) == (asset.source_units, asset.source_up_axis)
    assert second.num_frames == first.num_frames and second.fps == pytest.approx(first.fps)
    g1, p1 = motion_fk(first)
    g2, p2 = motion_fk(second)
    assert np.abs(p1 - p2).max() < 1e-6
    sites1 = end_site_positions(asset.skeleton, g1, p1)
    sites2 = end_site_positions(again.skeleton, g2, p2)
    assert sites1.shape == sites2.shape and (sites1.size == 0 or np.abs(sites1 - sites2).max() < 1e-6)


@pytest.mark.parametrize("doc", BANDAI, ids=_ids(BANDAI))
def test_bandai_fk_matches_matrix_chain(assets, doc):
    path = corpus_file(doc["file"])
    raw = parse_raw(path.read_text())
    reference = matrix_chain_positions(raw) * 0.01  # Bandai files are centimetres, +Y up
    asset = assets[doc["file"]]
    assert (asset.source_units, asset.source_up_axis) == ("cm", "Y")
    _, pos = motion_fk(next(iter(asset.motions.values())))
    order = [asset.skeleton.index[j["name"]] for j in raw["joints"]]
    assert reference.shape == pos.shape
    assert np.abs(pos[:, order] - reference).max() < 1e-6
    # Bandai animates every joint's translation: the reader must keep them.
    assert next(iter(asset.motions.values())).joint_translations is not None
