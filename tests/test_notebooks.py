"""The notebooks run top to bottom (nbclient, a fresh kernel each), with figures, and
the documentation site builds with warnings as errors."""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


def test_there_are_the_five_notebooks():
    assert [p.stem for p in NOTEBOOKS] == [
        "01_quickstart", "02_ppbh_geometry", "03_error_vs_time", "04_stiff_cases",
        "05_ground_truth_for_your_method"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs_with_figures(path):
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.read(path, as_version=4)
    # the notebooks are committed without outputs: the site executes them
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code")
    t0 = time.perf_counter()
    NotebookClient(nb, timeout=120, kernel_name="python3",
                   resources={"metadata": {"path": str(path.parent)}}).execute()
    elapsed = time.perf_counter() - t0
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    figures = [o for o in outputs if "image/png" in o.get("data", {})]
    assert figures, f"{path.name} drew no figure"
    print(f"{path.name}: {elapsed:.1f} s, {len(figures)} figures")


def test_documentation_site_builds_without_warnings(tmp_path):
    # notebooks are executed by the test above; here the site is built from them
    # unexecuted, so that every page, link and docstring is checked once
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html", "-q",
           "-D", "nb_execution_mode=off", "-d", str(tmp_path / "doctrees"),
           str(ROOT / "docs"), str(tmp_path / "html")]
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=env, timeout=600)
    assert r.returncode == 0, r.stderr[-5000:]
    html = tmp_path / "html"
    for page in ("index.html", "reference/index.html", "explanation/ppbh-method.html",
                 "notebooks/02_ppbh_geometry.html", "reference/generated/exactff.form_factors.html",
                 "reference/generated/exactff.plot.visible_graph.html"):
        assert (html / page).exists(), page


def test_every_public_name_is_in_the_reference():
    import exactff
    import exactff.catalog
    import exactff.plot
    import exactff.predicates
    import exactff.scenes
    import exactff.testing
    import exactff.testing.strategies
    import exactff.visibility

    text = (ROOT / "docs" / "reference" / "index.md").read_text()
    blocks = {}
    for block in text.split(".. currentmodule:: ")[1:]:
        module, _, rest = block.partition("\n")
        blocks[module.strip()] = {line.strip() for line in rest.split("```")[0].splitlines()
                                  if line.startswith("   ") and not line.strip().startswith(":")}
    for mod in (exactff, exactff.scenes, exactff.catalog, exactff.visibility,
                exactff.predicates, exactff.plot, exactff.testing, exactff.testing.strategies):
        listed = blocks.get(mod.__name__, set())
        missing = set(mod.__all__) - listed - {"catalog", "scenes", "__version__"}
        assert not missing, f"{mod.__name__}: {sorted(missing)} not in docs/reference/index.md"
