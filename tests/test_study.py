"""The error-versus-run-time study (issue 10): compare, its cache, exactff.plot and the
``exactff compare`` command."""

import json

import matplotlib
import numpy as np
import pytest

import exactff as ef
from exactff.cli import main
from exactff.reports import compare

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def small():
    return ef.scenes.office(300)


def test_compare_equals_a_direct_computation(small):
    rows = [3, 100, 250]
    rec = compare(small, ["hemicube", "ppbh"], samples=[1024], rows=rows)
    # the reference row by row through the public single-row interface
    ref = np.array([ef.form_factors(small, small.centroids[i], small.normals[i]) for i in rows])
    for r, m in zip(rec, (ef.Hemicube(samples=1024), ef.DiscretePPBH(samples=1024))):
        M = np.array([m.point_form_factors(small, small.centroids[i], small.normals[i])
                      for i in rows])
        err = M - ref
        assert r["samples"] == m.samples and r["rows"] == 3
        assert r["mean_abs_error"] == pytest.approx(np.abs(err).mean(), rel=1e-12)
        assert r["max_abs_error"] == pytest.approx(np.abs(err).max(), rel=1e-12)
        assert r["row_sum_error"] == pytest.approx(
            np.abs(M.sum(1) - ref.sum(1)).mean(), rel=1e-9, abs=1e-15)


def test_exact_runs_once_and_is_zero_against_itself(small):
    rec = compare(small, ["exact", "monte_carlo"], samples=[500, 1000], rows=[0, 7])
    assert [(r["method"], r["samples"] > 0) for r in rec] == [
        ("exact", False), ("monte_carlo", True), ("monte_carlo", True)]
    assert rec[0]["max_abs_error"] == 0.0 and rec[0]["samples"] == 0


def test_reference_cache(small, tmp_path):
    path = tmp_path / "ref.npz"
    a = compare(small, ["ppbh"], samples=[1024], rows=[1, 2], reference=path)
    assert path.exists() and a[0]["reference_time_per_row"] > 0
    b = compare(small, ["ppbh"], samples=[1024], rows=[1, 2], reference=path)
    assert b[0]["mean_abs_error"] == a[0]["mean_abs_error"]
    assert b[0]["reference_time_per_row"] == pytest.approx(a[0]["reference_time_per_row"])
    with pytest.raises(ValueError, match="other rows"):
        compare(small, ["ppbh"], samples=[1024], rows=[1, 3], reference=path)
    with pytest.raises(ValueError, match="another scene"):
        compare(ef.scenes.office(400), ["ppbh"], samples=[1024], rows=[1, 2], reference=path)


def _records():
    return [{"method": m, "samples": s, "mean_abs_error": k / s, "time_per_row": 1e-6 * s * k,
             "reference_time_per_row": 0.05}
            for k, m in ((1, "ppbh"), (2, "hemicube"), (3, "polar_plane"))
            for s in (1000, 4000, 16000)] + [
        {"method": "exact", "samples": 0, "mean_abs_error": 0.0, "time_per_row": 0.04,
         "reference_time_per_row": 0.05}]


@pytest.mark.parametrize("name", ["error_vs_samples", "time_vs_samples", "error_vs_time"])
def test_plots_draw_one_line_per_method(name):
    from exactff import plot

    ax = getattr(plot, name)(_records())
    labels = [ln.get_label() for ln in ax.lines]
    for m in ("ppbh", "hemicube", "polar_plane"):
        assert labels.count(m) == 1
        line = ax.lines[labels.index(m)]
        assert len(line.get_xdata()) == 3          # its three sample counts, in order
        assert list(line.get_xdata()) == sorted(line.get_xdata())
    assert ax.get_xscale() == ax.get_yscale() == "log"
    assert ax.get_xlabel() and ax.get_ylabel()
    if name == "error_vs_time":
        assert any(lab.startswith("exact (0.04") for lab in labels)   # the exact record's time
        assert "Pareto front" in labels
    else:
        assert "exact" not in labels                # no samples: not on these axes


def test_importing_exactff_does_not_import_matplotlib():
    import subprocess
    import sys

    code = "import sys, exactff; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_cli_compare_writes_every_file(tmp_path, capsys):
    out = tmp_path / "study"
    assert main(["compare", "office:300", "--methods", "hemicube,ppbh,exact", "--samples",
                 "1024,2048", "--rows", "3", "--seed", "5", "--out", str(out),
                 "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "| hemicube |" in text and "| exact | 0 |" in text
    for f in ("results.csv", "results.json", "reference.npz", "error_vs_samples.png",
              "time_vs_samples.png", "error_vs_time.png"):
        assert (out / f).stat().st_size > 0
    doc = json.loads((out / "results.json").read_text())
    assert doc["seed"] == 5 and len(doc["rows"]) == 3 and doc["polygons"] > 0
    rows = np.sort(np.random.default_rng(5).choice(doc["polygons"], 3, replace=False))
    assert doc["rows"] == rows.tolist()
    # the JSON holds compare's records for the same rows (errors are deterministic)
    again = compare(ef.scenes.office(300), ["hemicube", "ppbh", "exact"], samples=[1024, 2048],
                    rows=rows)
    for a, b in zip(doc["records"], again):
        assert (a["method"], a["samples"]) == (b["method"], b["samples"])
        assert a["mean_abs_error"] == b["mean_abs_error"]
    csv_lines = (out / "results.csv").read_text().strip().splitlines()
    assert len(csv_lines) == 1 + len(doc["records"])


@pytest.mark.parametrize("argv,needle", [
    (["--methods", "hemicub"], "--methods"),
    (["--methods", "ppbh", "--samples", "10,x"], "--samples"),
    (["--methods", "ppbh", "--samples", "0"], "--samples"),
    (["--methods", "ppbh", "--rows", "100000"], "--rows"),
    (["--methods", "ppbh", "--rows", "5:2"], "--rows"),
])
def test_cli_compare_bad_options_one_line(tmp_path, capsys, argv, needle):
    assert main(["compare", "box:1", "--out", str(tmp_path / "o"), "--no-progress"] + argv) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1
