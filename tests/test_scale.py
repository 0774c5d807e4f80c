"""Ground truth at scale: every executor gives the serial matrix bit for bit, dense and
sparse; outputs on disk (.npy, .zarr, .npz) resume after a SIGKILL without recomputing a
finished row; the scene reaches each worker once; the command line reaches a running
dask scheduler."""

import json
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import exactff as ef
from exactff import formfactors

from common import checkout_env
from scale_helpers import RecordingExact, read_log

ROOT = Path(__file__).resolve().parents[1]
SCENE = ef.scenes.furnished_box(2, [((0.2, 0.2, 0.0), (0.5, 0.6, 0.4)),
                                    ((0.6, 0.1, 0.3), (0.9, 0.4, 0.5))])


@pytest.fixture(scope="module")
def serial():
    return ef.form_factor_matrix(SCENE)


@pytest.fixture(scope="module")
def cluster():
    import distributed

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as c:
        yield c


def test_sparse_equals_dense_bit_for_bit(serial):
    S = ef.form_factor_matrix(SCENE, sparse=True)
    assert isinstance(S, sp.csr_array) and S.shape == serial.shape
    assert np.array_equal(S.toarray(), serial)
    assert S.nnz == np.count_nonzero(serial)
    assert np.all(S.data != 0)
    rows = [5, 0, 17]
    assert np.array_equal(ef.form_factor_matrix(SCENE, rows=rows, sparse=True).toarray(),
                          serial[rows])


@pytest.mark.parametrize("sparse", [False, True])
def test_executors_give_the_serial_matrix(serial, sparse):
    def dense(M):
        return M.toarray() if sp.issparse(M) else np.asarray(M)

    assert np.array_equal(dense(ef.form_factor_matrix(SCENE, jobs=2, sparse=sparse)), serial)
    with ProcessPoolExecutor(2) as ex:
        assert np.array_equal(dense(ef.form_factor_matrix(SCENE, executor=ex, chunk_rows=3,
                                                          sparse=sparse)), serial)
    with ThreadPoolExecutor(2) as ex:
        assert np.array_equal(dense(ef.form_factor_matrix(SCENE, executor=ex, sparse=sparse)),
                              serial)


@pytest.mark.parametrize("sparse", [False, True])
def test_dask_gives_the_serial_matrix(serial, cluster, sparse):
    from distributed import Client

    with Client(cluster) as client:
        for ex in (client, client.get_executor()):
            M = ef.form_factor_matrix(SCENE, executor=ex, chunk_rows=4, sparse=sparse)
            assert np.array_equal(M.toarray() if sparse else M, serial)


def _per_process(log):
    seen = {}
    for pid, sid, had, _ in read_log(log):
        seen.setdefault(pid, []).append((sid, had))
    return seen


def test_the_scene_reaches_each_worker_once(tmp_path, cluster):
    from distributed import Client

    runs = {"jobs": lambda m: ef.form_factor_matrix(SCENE, method=m, jobs=2, chunk_rows=2)}

    def with_dask(m):
        with Client(cluster) as client:
            return ef.form_factor_matrix(SCENE, method=m, executor=client, chunk_rows=2)
    runs["dask"] = with_dask
    for name, run in runs.items():
        log = tmp_path / f"{name}.log"
        run(RecordingExact(str(log)))
        seen = _per_process(log)
        assert sum(len(v) for v in seen.values()) == len(SCENE)
        for pid, calls in seen.items():
            # one scene object per worker process, its BSP tree built at most once (a
            # forked pool's workers may inherit it built)
            assert len({sid for sid, _ in calls}) == 1, (name, pid)
            assert [had for _, had in calls].count("0") <= 1, (name, pid)
    # the baseline this replaces: a scene sent with every block is a new object each time
    # (a generic executor's process keeps the first one it got and its BSP tree)
    log = tmp_path / "pool.log"
    with ProcessPoolExecutor(1) as ex:
        ef.form_factor_matrix(SCENE, method=RecordingExact(str(log)), executor=ex, chunk_rows=2)
    [(pid, calls)] = _per_process(log).items()
    assert len({sid for sid, _ in calls}) == 1 and [h for _, h in calls].count("0") == 1
    log = tmp_path / "old.log"
    m = RecordingExact(str(log))
    with ProcessPoolExecutor(1) as ex:
        for rows in np.array_split(np.arange(len(SCENE)), 4):
            ex.submit(formfactors.PointRows(m, False), SCENE, rows).result()
    [(pid, calls)] = _per_process(log).items()
    assert [h for _, h in calls].count("0") == 4        # a BSP tree built per block


# ---------------------------------------------------------------------------------------
# outputs on disk
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("suffix, sparse", [(".npy", False), (".zarr", False), (".npz", True)])
def test_outputs_round_trip_and_refuse_other_computations(tmp_path, serial, suffix, sparse):
    path = str(tmp_path / ("m" + suffix))
    M = ef.form_factor_matrix(SCENE, out=path, sparse=sparse, chunk_rows=5)
    back = ef.load_matrix(path)
    dense = back.toarray() if sparse else np.asarray(back[:])
    assert np.array_equal(dense, serial)
    again = ef.form_factor_matrix(SCENE, out=path, sparse=sparse, chunk_rows=5)  # finished
    assert np.array_equal(again.toarray() if sparse else np.asarray(again[:]), serial)
    assert not os.path.exists(str(tmp_path / "m.done.npy"))
    assert not os.path.exists(str(tmp_path / "m.parts"))
    with pytest.raises(ValueError, match="not written by this computation"):
        ef.form_factor_matrix(SCENE, out=path, sparse=sparse, two_sided=True, chunk_rows=5)
    with pytest.raises(ValueError, match="not written by this computation"):
        ef.form_factor_matrix(SCENE, out=path, sparse=sparse, rows=range(10), chunk_rows=5)
    del M


@pytest.mark.parametrize("name, sparse, written", [("m", False, "m.npy"), ("m", True, "m.npz"),
                                                   ("m.v2", False, "m.v2.npy")])
def test_out_without_a_known_suffix_gets_the_formats_suffix(tmp_path, serial, name, sparse,
                                                            written):
    # DESIGN 5: out="m" writes m.npy (dense) or m.npz (sparse=True), as np.save does
    M = ef.form_factor_matrix(SCENE, out=tmp_path / name, sparse=sparse, chunk_rows=5)
    assert sorted(os.listdir(tmp_path)) == sorted([written, written[:-4] + ".meta.json"])
    back = ef.load_matrix(tmp_path / written)
    assert sp.issparse(back) == sparse
    assert np.array_equal(back.toarray() if sparse else np.asarray(back), serial)
    assert np.array_equal(M.toarray() if sparse else np.asarray(M), serial)
    # the same path again resumes the finished file instead of starting another
    again = ef.form_factor_matrix(SCENE, out=str(tmp_path / name), sparse=sparse, chunk_rows=5)
    assert np.array_equal(again.toarray() if sparse else np.asarray(again), serial)
    assert len(os.listdir(tmp_path)) == 2


def test_two_formats_of_one_name_are_refused_with_the_reason(tmp_path, serial):
    dense = str(tmp_path / "m.npy")
    ef.form_factor_matrix(SCENE, out=dense, chunk_rows=5)
    with pytest.raises(ValueError, match="same name in another format"):
        ef.form_factor_matrix(SCENE, out=str(tmp_path / "m.npz"), sparse=True, chunk_rows=5)
    # the first output's record is untouched: it still reopens as finished
    assert np.array_equal(np.asarray(ef.form_factor_matrix(SCENE, out=dense, chunk_rows=5)[:]),
                          serial)


def test_bad_outputs_and_options(tmp_path):
    with pytest.raises(ValueError, match="sparse=True"):
        ef.form_factor_matrix(SCENE, out=tmp_path / "a.npz")
    with pytest.raises(ValueError, match=r"\.npz"):
        ef.form_factor_matrix(SCENE, out=tmp_path / "a.npy", sparse=True)
    for bad in (3, b"m.npy"):
        with pytest.raises(TypeError, match="out: expected a path"):
            ef.form_factor_matrix(SCENE, out=bad)
    with pytest.raises(ValueError, match="jobs"):
        ef.form_factor_matrix(SCENE, jobs=0)
    with pytest.raises(ValueError, match="not both"):
        with ThreadPoolExecutor(1) as ex:
            ef.form_factor_matrix(SCENE, jobs=2, executor=ex)
    with pytest.raises(ValueError, match="chunk_rows"):
        ef.form_factor_matrix(SCENE, chunk_rows=0)
    with pytest.raises(FileNotFoundError):
        ef.load_matrix(tmp_path / "none.npy")
    with pytest.raises(FileNotFoundError, match="none.txt.npy"):
        ef.load_matrix(tmp_path / "none.txt")


def test_load_matrix_finds_the_suffix_out_wrote(tmp_path, caplog):
    # issue 53: out="m" writes m.npy (dense) or m.npz (sparse), and a .zarr store keeps
    # its name; load_matrix("m") reads whichever exists and says which, as np.load users
    # expect. The values: against the matrix computed in memory.
    import logging

    F = ef.form_factor_matrix(SCENE)
    ef.form_factor_matrix(SCENE, out=tmp_path / "dense")
    ef.form_factor_matrix(SCENE, sparse=True, out=tmp_path / "sparse")
    ef.form_factor_matrix(SCENE, out=tmp_path / "chunked.zarr")
    with caplog.at_level(logging.INFO, logger="exactff"):
        dense = ef.load_matrix(tmp_path / "dense")
        sparse = ef.load_matrix(tmp_path / "sparse")
        chunked = ef.load_matrix(tmp_path / "chunked")
    np.testing.assert_array_equal(np.asarray(dense), F)
    np.testing.assert_array_equal(sparse.toarray(), F)
    np.testing.assert_array_equal(np.asarray(chunked[:]), F)
    read = [r.getMessage() for r in caplog.records]
    for name in ("dense.npy", "sparse.npz", "chunked.zarr"):
        assert any(name in m for m in read), read
    # two outputs of one name: no guess
    np.save(tmp_path / "sparse.npy", F)
    with pytest.raises(ValueError, match="names 2 outputs"):
        ef.load_matrix(tmp_path / "sparse")


KILLED = """
import sys, exactff as ef
sys.path.insert(0, {tests!r})
from scale_helpers import RecordingExact
scene = ef.scenes.furnished_box(2, [((0.2, 0.2, 0.0), (0.5, 0.6, 0.4)),
                                    ((0.6, 0.1, 0.3), (0.9, 0.4, 0.5))])
ef.form_factor_matrix(scene, method=RecordingExact({log!r}), out={out!r}, sparse={sparse},
                      chunk_rows=2)
"""


def _done_rows(path, suffix):
    stem = path[: -len(suffix)]
    if suffix == ".npz":
        done = set()
        parts = stem + ".parts"
        for name in os.listdir(parts) if os.path.isdir(parts) else []:
            if name.endswith(".npz") and not name.endswith(".tmp.npz"):
                with np.load(os.path.join(parts, name)) as z:
                    done |= set(z["pos"].tolist())
        return done
    try:
        return set(np.flatnonzero(np.load(stem + ".done.npy")).tolist())
    except (OSError, ValueError, EOFError):
        return set()


@pytest.mark.parametrize("suffix, sparse", [(".npy", False), (".zarr", False), (".npz", True)])
def test_sigkill_then_resume_gives_the_identical_matrix(tmp_path, serial, suffix, sparse):
    out, log = str(tmp_path / ("m" + suffix)), str(tmp_path / "killed.log")
    code = KILLED.format(tests=str(ROOT / "tests"), log=log, out=out, sparse=sparse)
    # (its rows 20 ms each at least: 36 of them outlast the polls that see 8 done, which
    # rows of about 1 ms could all finish between; the clean-clone CI saw that once)
    env = checkout_env() | {"EXACTFF_TEST_ROW_DELAY": "0.02"}
    proc = subprocess.Popen([sys.executable, "-c", code], cwd=tmp_path, env=env)
    deadline = time.time() + 120
    while len(_done_rows(out, suffix)) < 8 and time.time() < deadline and proc.poll() is None:
        time.sleep(0.02)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    done = _done_rows(out, suffix)
    assert 8 <= len(done) < len(SCENE), "the run was not killed part-way"
    # resume in this process with the same computation; log what it computes
    method = RecordingExact(log)
    computed = len(read_log(log))
    M = ef.form_factor_matrix(SCENE, method=method, out=out, sparse=sparse, chunk_rows=2)
    resumed = read_log(log)[computed:]
    centroids = {tuple(np.round(c, 12)) for c in SCENE.centroids[sorted(done)]}
    again = [tuple(np.round(json.loads(r[3]), 12)) for r in resumed]
    assert not centroids & set(again), "a finished row was computed again"
    assert len(again) == len(SCENE) - len(done)
    dense = M.toarray() if sparse else np.asarray(M[:])
    assert np.array_equal(dense, serial)
    back = ef.load_matrix(out)
    assert np.array_equal(back.toarray() if sparse else np.asarray(back[:]), serial)


def test_an_unfinished_output_is_not_read_as_a_matrix(tmp_path):
    path = str(tmp_path / "m.npy")
    ef.form_factor_matrix(SCENE, out=path)
    np.save(str(tmp_path / "m.done.npy"), np.arange(len(SCENE)) < 5)
    with pytest.raises(ValueError, match="not finished"):
        ef.load_matrix(path)


# ---------------------------------------------------------------------------------------
# the command line
# ---------------------------------------------------------------------------------------
def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "exactff", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300, env=checkout_env())


def test_cli_scheduler_sparse_and_jobs(tmp_path, serial, cluster):
    scene_file = tmp_path / "scene.json"
    scene_file.write_text(SCENE_JSON())
    r = _cli("matrix", str(scene_file), "--scheduler", cluster.scheduler_address, "--sparse",
             "--no-progress", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    S = ef.load_matrix(tmp_path / "scene_ff.npz")
    assert np.array_equal(S.toarray(), serial)
    r = _cli("matrix", str(scene_file), "--jobs", "2", "-o", "d.zarr", "--no-progress",
             cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert np.array_equal(np.asarray(ef.load_matrix(tmp_path / "d.zarr")[:]), serial)
    for bad, msg in ((["--jobs", "2", "--scheduler", cluster.scheduler_address], "give one"),
                     (["--sparse", "-o", "x.npy"], "--sparse writes a .npz"),
                     (["-o", "x.npz"], "needs --sparse"),
                     (["--scheduler", "tcp://127.0.0.1:9", "--scheduler-timeout", "2"],
                      "cannot connect")):
        r = _cli("matrix", str(scene_file), "--no-progress", *bad, cwd=tmp_path)
        assert r.returncode == 2 and msg in r.stderr and "Traceback" not in r.stderr, (bad, r.stderr)
    # another suffix is kept and the format's appended, as np.save does
    r = _cli("matrix", str(scene_file), "--no-progress", "-o", "x.txt", cwd=tmp_path)
    assert r.returncode == 0 and "-> x.txt.npy" in r.stdout, r.stderr
    assert np.array_equal(np.asarray(ef.load_matrix(tmp_path / "x.txt.npy")), serial)


def SCENE_JSON():
    import json

    return json.dumps({"schema": "exactff-scene/1",
                       "surfaces": [{"vertices": P.tolist()} for P in SCENE.polygons]})
