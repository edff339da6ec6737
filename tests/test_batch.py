"""``infuse batch`` / ``run_batch`` in this process and on a process pool: the output tree, outputs
equal to ``infuse retarget``'s, failures reported while the rest completes, resuming, packs, the
bounded window of units in flight and output naming."""
from __future__ import annotations

import concurrent.futures as cf
import os
import shutil
import sys
from pathlib import Path

import pytest

import infuse
from infuse.cli import main
from infuse.errors import MissingFeatureError, UsageError
from infuse.grounding import foot_height
from infuse.mapping import map_skeleton
from infuse_batch import backends, jobs, run_batch
from infuse_batch.manifest import FILENAME

from batch_support import BANDAI, MOTIONS, UTAH, XBOT, character_files, expected_outputs, motion_files, tree
from corpus_data import corpus_file, require_corpus

FOX = "projectlookingglass-glb/Fox.glb"


@pytest.fixture(scope="module")
def local(tmp_path_factory):
    """The shared inputs run once in this process, two motion files per unit."""
    require_corpus()
    out = tmp_path_factory.mktemp("batch") / "out"
    mp = pytest.MonkeyPatch()
    mp.setattr(jobs, "CHUNK_FILES", 2)
    try:
        result = run_batch(character_files(), motions=motion_files(), out=out, workers=0, progress=False)
    finally:
        mp.undo()
    return out, result


def test_every_character_gets_every_clip(local):
    out, result = local
    assert result.ok and result.exit_code == 0, result.failures
    assert set(tree(out)) == expected_outputs()
    assert result.items == 12 and result.skipped == 0 and result.written == 12 and result.units == 4
    frames = sum(infuse.load(f).num_frames for f in motion_files())
    assert result.frames == 2 * frames
    assert (out / FILENAME).is_file()


def test_glb_output_is_the_character_with_the_clip(local):
    out, _ = local
    xbot = infuse.load(corpus_file(XBOT))
    walk = infuse.load(corpus_file(BANDAI.format("walk_normal")))
    got = infuse.load(out / "Xbot" / "dataset-1_walk_normal_001.glb")
    assert got.skeleton.names == xbot.skeleton.names
    assert list(got.motions) == list(walk.motions)
    clip = next(iter(got.motions.values()))
    assert clip.num_frames == walk.num_frames
    doc, original = got.payload.document.json, xbot.payload.document.json
    assert len(doc["meshes"]) == len(original["meshes"]) > 0
    assert len(doc["animations"]) == 1
    assert abs(foot_height(got, map_skeleton(got), clip)) < 1e-5  # its soles touch y = 0


def test_first_clip_of_a_chunk_equals_infuse_retarget(local, tmp_path, capsys):
    """A chunk's first clip is its group's reference, as a lone clip is for ``infuse retarget``:
    the same bytes come out."""
    out, _ = local
    for motion in (BANDAI.format("run_normal"), "smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Run001.skm"):
        single = tmp_path / (Path(motion).stem + ".bvh")
        code = main(["retarget", str(corpus_file(motion)), "--to", str(corpus_file(UTAH)), "-o", str(single)])
        assert code == 0, capsys.readouterr().err
        assert (out / "test_utah" / single.name).read_bytes() == single.read_bytes()


def test_pool_gives_the_same_bytes(local, tmp_path):
    out, _ = local
    pooled = tmp_path / "pool"
    mp = pytest.MonkeyPatch()
    mp.setattr(jobs, "CHUNK_FILES", 2)
    try:
        result = run_batch(character_files(), motions=motion_files(), out=pooled, workers=2, progress=False)
    finally:
        mp.undo()
    assert result.ok, result.failures
    assert tree(pooled) == tree(out)


def _corrupt_inputs(folder: Path) -> tuple[Path, Path]:
    folder.mkdir(parents=True, exist_ok=True)
    text = corpus_file(BANDAI.format("walk_masculinity")).read_bytes()
    broken_motion = folder / "broken_walk.bvh"
    broken_motion.write_bytes(text[: len(text) // 3])  # ends inside the motion block
    broken_character = folder / "broken.glb"
    broken_character.write_bytes(b"glTF\x02\x00\x00\x00" + os.urandom(64))
    return broken_motion, broken_character


def test_corrupt_inputs_are_reported_and_the_rest_completes(tmp_path, capsys):
    require_corpus()
    broken_motion, broken_character = _corrupt_inputs(tmp_path / "in")
    good = [str(corpus_file(BANDAI.format("walk_normal"))), str(corpus_file(MOTIONS[3]))]
    out = tmp_path / "out"
    code = main(["batch", str(corpus_file(XBOT)), str(broken_character), "--motions", good[0], "--motions", good[1],
                 "--motions", str(broken_motion), "-o", str(out), "--workers", "0"])
    stdout, stderr = capsys.readouterr()
    assert code == 2, stdout + stderr
    assert set(tree(out)) == {"Xbot/dataset-1_walk_normal_001.glb", "Xbot/ChrUtah_Walk001.glb"}
    assert "2 failures:" in stdout
    failures = [ln.strip() for ln in stdout.splitlines() if ln.startswith("  ")]
    assert any(ln.startswith(f"{broken_motion}:") for ln in failures), stdout
    assert any(ln.startswith(f"{broken_character}:") for ln in failures), stdout
    assert "Traceback" not in stdout + stderr


def test_unusable_input_exits_3(tmp_path):
    require_corpus()
    result = run_batch([str(corpus_file(XBOT))], motions=[str(corpus_file(BANDAI.format("walk_normal"))),
                                                           str(corpus_file(FOX))], out=tmp_path, workers=0, progress=False)
    assert result.exit_code == 3
    assert [f.file for f in result.failures] == [str(corpus_file(FOX))]
    assert "humanoid" in result.failures[0].reason
    assert set(tree(tmp_path)) == {"Xbot/dataset-1_walk_normal_001.glb"}


def test_lost_unit_is_reported_and_the_rest_completes(tmp_path):
    """A unit whose worker never answers (it died, the cluster went away) fails its files only."""
    require_corpus()

    class Flaky(cf.Executor):
        def submit(self, fn, unit):
            future = cf.Future()
            if any("run_normal" in s.path for s in unit.motions):
                future.set_exception(RuntimeError("worker killed"))
            else:
                future.set_result(fn(unit))
            return future

    mp = pytest.MonkeyPatch()
    mp.setattr(jobs, "CHUNK_FILES", 1)
    try:
        result = run_batch(character_files(), motions=motion_files(), out=tmp_path, executor=Flaky(), progress=False)
    finally:
        mp.undo()
    assert [f.file for f in result.failures] == [str(corpus_file(BANDAI.format("run_normal")))]
    assert "worker killed" in result.failures[0].reason and result.exit_code == 1
    assert set(tree(tmp_path)) == {p for p in expected_outputs() if "run_normal" not in p}


def test_resume_skips_what_is_done_and_redoes_what_changed(tmp_path):
    require_corpus()
    own = tmp_path / "in" / "walk.bvh"
    own.parent.mkdir()
    shutil.copyfile(corpus_file(BANDAI.format("walk_normal")), own)
    motions = [str(own), str(corpus_file(MOTIONS[3]))]
    out = tmp_path / "out"
    first = run_batch(character_files(), motions=motions, out=out, workers=0, progress=False)
    assert first.ok and first.written == 4
    stamps = {p: p.stat().st_mtime_ns for p in out.rglob("*.*") if p.name != FILENAME}

    again = run_batch(character_files(), motions=motions, out=out, workers=0, progress=False)
    assert (again.skipped, again.written, again.units) == (4, 0, 0)

    os.utime(own, ns=(own.stat().st_atime_ns, own.stat().st_mtime_ns + 10**9))  # touched, same bytes
    (out / "test_utah" / "ChrUtah_Walk001.bvh").unlink()  # an output lost
    with open(out / FILENAME, "a") as f:
        f.write('{"done": [{"charac')  # a line torn by a stopped job
    third = run_batch(character_files(), motions=motions, out=out, workers=0, progress=False)
    assert (third.skipped, third.written) == (3, 1)
    assert all(p.stat().st_mtime_ns == t for p, t in stamps.items() if p.name != "ChrUtah_Walk001.bvh")

    with open(own, "ab") as f:
        f.write(b"\n")  # new bytes: both characters' outputs of it are redone
    fourth = run_batch(character_files(), motions=motions, out=out, workers=0, progress=False)
    assert (fourth.skipped, fourth.written) == (2, 2)

    other = run_batch(character_files(), motions=motions, out=out, workers=0, progress=False, format="bvh")
    assert other.written == 4 and (out / "Xbot" / "walk.bvh").is_file()  # other settings: not the same outputs
    fresh = run_batch(character_files(), motions=motions, out=out, workers=0, progress=False, resume=False)
    assert fresh.written == 4


def test_packs_give_one_infusion_cache_per_character(tmp_path):
    require_corpus()
    from infuse.packs import build_pack, import_bvh_folder, infuse_character

    data = corpus_file(BANDAI.format("walk_normal")).parent
    pack = import_bvh_folder(data, tmp_path / "pack", name="walks", pattern="dataset-1_walk_*_001.bvh")
    build_pack(pack)
    out = tmp_path / "out"
    result = run_batch(character_files(), packs=str(pack.parent), out=out, workers=0, progress=False)
    assert result.ok, result.failures
    assert set(tree(out)) == {f"{c}/infusion.{e}" for c in ("Xbot", "test_utah") for e in ("npz", "json")}
    infusion = infuse_character(str(corpus_file(XBOT)), [str(pack.parent)], cache=out / "Xbot" / "infusion.npz")
    assert infusion.cached and len(infusion.spaces["walks"].clips) == 3
    again = run_batch(character_files(), packs=str(pack.parent), out=out, workers=0, progress=False)
    assert (again.items, again.skipped, again.written) == (2, 2, 0)


def test_cli_progress_and_summary(tmp_path, capsys):
    require_corpus()
    code = main(["batch", *character_files(), "--motions", motion_files()[0], "-o", str(tmp_path), "--workers", "0"])
    stdout, stderr = capsys.readouterr()
    assert code == 0, stderr
    assert "wrote 2 files (2 clips" in stdout and "0 of 2 items already done" in stdout
    bar = [ln for ln in stderr.splitlines() if ln.startswith("batch ")]
    assert bar and bar[-1].startswith("batch 100% [") and "] 2/2 left 0:00 elapsed" in bar[-1], stderr
    assert "items/s" in bar[-1] and "clip-frames/s" in bar[-1]


def test_cluster_without_dask_says_what_to_install(tmp_path, monkeypatch):
    require_corpus()
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(MissingFeatureError, match=r"infuse-anim-batch\[dask\]"):
        run_batch(character_files(), motions=motion_files()[:1], out=tmp_path, cluster="tcp://127.0.0.1:8786")


def test_usage_errors(tmp_path):
    require_corpus()
    with pytest.raises(UsageError, match="motions to retarget, packs"):
        run_batch(character_files(), out=tmp_path)
    with pytest.raises(UsageError, match="no such character"):
        run_batch([str(tmp_path / "nobody*.glb")], motions=motion_files(), out=tmp_path)
    with pytest.raises(UsageError, match="format"):
        run_batch(character_files(), motions=motion_files(), out=tmp_path, format="fbx")


def test_window_bounds_units_in_flight():
    """However many units there are, at most ``slots`` are submitted and not yet collected."""
    class Counting(backends.InProcess):
        slots = 3

        def __init__(self):
            self.open, self.most = 0, 0

        def submit(self, unit):
            self.open += 1
            self.most = max(self.most, self.open)
            future = cf.Future()
            future.set_result(unit)
            return future

        def result(self, handle):
            self.open -= 1
            return handle.result()

    backend = Counting()
    seen = [u for u, _ in backends.stream(backend, iter(range(50)))]
    assert sorted(seen) == list(range(50)) and backend.most == 3


def test_names_in_the_output_tree(tmp_path):
    for rel in ("a/walk.bvh", "a/walk.skm", "a/deep/run.bvh", "b/walk.bvh", "c/x.glb", "d/x.glb", "c/y.glb"):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_bytes(b"")
    out = tmp_path / "a" / "out"
    (out / "Xbot").mkdir(parents=True)
    (out / "Xbot" / "old.bvh").write_bytes(b"")  # an earlier output inside a motion folder is not an input
    names = [s.name for s in jobs.motion_sources([str(tmp_path / "a")], out)]
    assert names == ["deep/run", "walk.bvh", "walk.skm"]
    names = [s.name for s in jobs.motion_sources([str(tmp_path / "a" / "walk.bvh"), str(tmp_path / "b")], out)]
    assert names == ["a/walk", "b/walk"]
    chars = [s.name for s in jobs.character_sources([str(tmp_path / "c" / "*.glb"), str(tmp_path / "d")])]
    assert chars == ["c/x", "c/y", "d/x"]
    assert [s.name for s in jobs.character_sources([str(tmp_path / "c")])] == ["x", "y"]


def test_chunks_keep_to_one_folder_and_the_limits(tmp_path, monkeypatch):
    monkeypatch.setattr(jobs, "CHUNK_BYTES", 100)
    files = []
    for rel, size in (("a/1.bvh", 10), ("a/2.bvh", 10), ("a/3.bvh", 95), ("a/4.bvh", 10), ("b/5.bvh", 10)):
        path = tmp_path / rel
        path.parent.mkdir(exist_ok=True)
        path.write_bytes(b"x" * size)
        files.append(jobs.Source(str(path), rel))
    assert [[s.name for s in c] for c in jobs.chunks(files)] == [["a/1.bvh", "a/2.bvh"], ["a/3.bvh"], ["a/4.bvh"], ["b/5.bvh"]]


def test_batch_hands_the_character_s_meshes_to_the_retargeter():
    """The soles of feet without a ball joint come from the mesh: batch passes the character's meshes to
    ``prepare`` as ``infuse retarget`` does (none when they cannot be decoded)."""
    from dataclasses import replace

    import numpy as np

    from infuse.plugin_types import Retargeter
    from infuse_batch.work import _Loaded, _planner

    seen = {}

    def prepare(source_skeleton, source_mapping, target_skeleton, target_mapping, **options):
        seen.update(options)
        return lambda motion: motion

    def broken():
        raise ValueError("bad accessor")

    xbot = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    clip = infuse.Motion(xbot.skeleton, 30.0, np.tile(xbot.skeleton.rest_rotations, (2, 1, 1)), np.zeros((2, 3)))
    spy = Retargeter("spy", lambda *a, **k: None, prepare=prepare)
    _planner(spy, clip, None, _Loaded(xbot, None, {}, 0.0), "a.bvh", "b.glb")
    assert len(seen["target_meshes"]) > 0 and seen["target_meshes"] is xbot.meshes and seen["source_motion"] is clip
    unreadable = replace(xbot, mesh_loader=broken)
    _planner(spy, clip, None, _Loaded(unreadable, None, {}, 0.0), "a.bvh", "b.glb")
    assert seen["target_meshes"] == ()
