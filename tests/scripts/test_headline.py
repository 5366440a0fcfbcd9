"""scripts/headline.py --check against a copy of the repository's README and results: it passes on them as
committed and fails on a README edited to hide a miss, on stale figures, and marks a run from a dirty tree."""
import json
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

SOURCE = pathlib.Path(os.environ.get("HOVS_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
SCRIPT = SOURCE / "scripts" / "headline.py"
FILES = ["README.md", "results/validate-full/metrics.json", "results/benchmarks/render_ratio.json"]


@pytest.fixture
def root(tmp_path):
    for f in FILES:
        (tmp_path / f).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(SOURCE / f, tmp_path / f)
    return tmp_path


def check(root):
    return subprocess.run([sys.executable, str(SCRIPT), "--check", "--root", str(root)], capture_output=True,
                          text=True).returncode


def headline(root):
    text = (root / "README.md").read_text()
    return text[text.index("<!-- headline"):text.index("<!-- headline end -->")]


def test_the_committed_readme_matches_its_results(root):
    assert check(root) == 0


def test_a_miss_shown_as_met_fails(root):
    readme = (root / "README.md").read_text()
    if "not met yet" not in headline(root):
        pytest.skip("the committed results meet every target: no miss to hide")
    (root / "README.md").write_text(readme.replace("| not met yet (target) |", "| met (target) |", 1))
    assert check(root) == 1


def test_a_miss_left_out_fails(root):
    lines = (root / "README.md").read_text().splitlines(keepends=True)
    misses = [i for i, l in enumerate(lines) if "not met yet" in l and l.startswith("|")]
    if not misses:
        pytest.skip("the committed results meet every target: no miss to leave out")
    del lines[misses[0]]
    (root / "README.md").write_text("".join(lines))
    assert check(root) == 1


def test_a_check_that_stops_passing_shows_up_as_not_met(root):
    metrics_path = root / "results/validate-full/metrics.json"
    m = json.loads(metrics_path.read_text())
    target = next(c for c in m["checks"] if c["pass"] and not c["gate"])
    target["pass"] = False
    metrics_path.write_text(json.dumps(m))
    assert check(root) == 1
    subprocess.run([sys.executable, str(SCRIPT), "--root", str(root)], check=True)
    assert check(root) == 0
    assert target["name"] in headline(root) or "not met yet" in headline(root)
    before = headline(root).count("not met yet")
    target["pass"] = True
    metrics_path.write_text(json.dumps(m))
    subprocess.run([sys.executable, str(SCRIPT), "--root", str(root)], check=True)
    assert headline(root).count("not met yet") == before - 1


def test_a_run_from_a_dirty_tree_says_so(root):
    metrics_path = root / "results/validate-full/metrics.json"
    m = json.loads(metrics_path.read_text())
    m["versions"]["hovs"] = "0.1.0 (abc1234-dirty)"
    metrics_path.write_text(json.dumps(m))
    subprocess.run([sys.executable, str(SCRIPT), "--root", str(root)], check=True)
    assert "uncommitted changes" in headline(root)


def test_a_slow_render_is_not_met(root):
    path = root / "results/benchmarks/render_ratio.json"
    b = json.loads(path.read_text())
    for x in b["benchmarks"]:
        if x["name"] == "BM_RenderFrame/4/1/iterations:3/real_time_median":
            x["real_time"], x["time_unit"] = 1600.0, "ms"
    path.write_text(json.dumps(b))
    subprocess.run([sys.executable, str(SCRIPT), "--root", str(root)], check=True)
    row = next(l for l in headline(root).splitlines() if l.startswith("| render, "))
    assert "not met yet" in row and "1600 ms" in row
