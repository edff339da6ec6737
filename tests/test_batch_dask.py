"""The same batch three ways: in this process, on the local process pool, and on a
``dask.distributed`` cluster of worker processes on loopback (the CLI's ``--cluster``). The three
output trees are byte for byte the same."""
from __future__ import annotations

import distributed  # the [dask] extra of infuse-anim-batch
import pytest

from infuse.cli import main
from infuse_batch import jobs, run_batch

from batch_support import character_files, expected_outputs, motion_files, tree
from corpus_data import require_corpus


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None, protocol="tcp") as c:
        yield c


def test_in_process_pool_and_dask_write_the_same_bytes(tmp_path, cluster, capsys, monkeypatch):
    require_corpus()
    monkeypatch.setattr(jobs, "CHUNK_FILES", 2)  # several units per folder
    runs = {}
    for name, options in (("inline", dict(workers=0)), ("pool", dict(workers=2))):
        result = run_batch(character_files(), motions=motion_files(), out=tmp_path / name, progress=False, **options)
        assert result.ok and result.written == 12, result.failures
        runs[name] = tree(tmp_path / name)
    motions = [a for m in motion_files() for a in ("--motions", m)]
    code = main(["batch", *character_files(), *motions, "-o", str(tmp_path / "dask"), "--cluster",
                 cluster.scheduler_address, "--quiet"])
    stdout, stderr = capsys.readouterr()
    assert code == 0, stdout + stderr
    assert "wrote 12 files" in stdout
    runs["dask"] = tree(tmp_path / "dask")
    assert set(runs["inline"]) == expected_outputs()
    assert runs["pool"] == runs["inline"]
    assert runs["dask"] == runs["inline"]


def test_dask_reports_a_corrupt_input_and_completes_the_rest(tmp_path, cluster):
    require_corpus()
    broken = tmp_path / "in" / "broken.skm"
    broken.parent.mkdir()
    broken.write_text("# SmartBody motion\nSkMotion\nname broken\nchannels 2\n  base XPos\n  base YPos\nframes 3\nkt 0 fr 1 2\n")
    out = tmp_path / "out"
    client = distributed.Client(cluster.scheduler_address, set_as_default=False)
    try:
        result = run_batch(character_files(), motions=motion_files() + [str(broken)], out=out, cluster=client,
                           progress=False)
    finally:
        client.close()
    assert [f.file for f in result.failures] == [str(broken)] and result.exit_code == 2
    assert set(tree(out)) == expected_outputs()
