"""The experiment report of `robodesign run`: each best solution links to its 3-D view, and the page fits a
1400 px window (tables scroll inside themselves), checked in headless Chromium when it is installed."""
import json
import re
import shutil
from pathlib import Path

import pytest

from robodesign.cli.entry import main
from robodesign.formats.solution import load_solution
from robodesign.viewer.html import decode_page_data

CONFIG = """
name: report
modules: robodesign_arm
tasks: [robodesign/pick_and_place, robodesign/welding_seam]
cost: cyc
optimizers: [random, genetic]
budget: 10evals
seeds: [0, 1]
batch_size: 2
executor: serial
"""
CHROMIUM = next((p for p in ("/usr/bin/chromium", shutil.which("chromium") or "") if p and Path(p).exists()), None)


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("report")
    (tmp / "cfg.yaml").write_text(CONFIG)
    out = tmp / "res"
    assert main(["run", str(tmp / "cfg.yaml"), "--out", str(out), "--progress", "none"]) == 0
    return out


@pytest.mark.slow
def test_each_best_solution_links_to_its_3d_view(report):
    page = (report / "index.html").read_text()
    best_files = sorted(p.relative_to(report).as_posix() for p in (report / "best").rglob("*-seed*.json")
                        if not p.name.endswith(".verdict.json"))
    assert best_files  # pick_and_place has feasible designs within 10 evaluations for this config
    for rel in best_files:
        view = rel[:-len(".json")] + "_view.html"
        assert f"<a href='{rel}'>{rel}</a> · <a href='{view}'>3D view</a>" in page  # checked best solutions table
        data = decode_page_data((report / view).read_text())
        sol = load_solution(report / rel)
        assert data["info"]["modules"] == list(sol.module_order)
        # best/<task ID>/<optimizer>-seed<N>.json (welding_seam, without basePlacement, is solved too since its
        # base is searched around its goals)
        assert data["info"]["task"] == "/".join(rel.split("/")[1:-1])
        assert data["animation"]["shape"][0] >= 2 and data["info"]["samples"] == len(sol.trajectory.t)
    # the "Best robots" row of the task links the view of its best run
    row = re.search(r"<tr><td>robodesign/pick_and_place</td><td>(\w+)</td><td>(\d+)</td>.*?</tr>", page).group(0)
    opt, seed = re.search(r"<td>robodesign/pick_and_place</td><td>(\w+)</td><td>(\d+)</td>", row).groups()
    assert f"<a href='best/robodesign/pick_and_place/{opt}-seed{seed}_view.html'>3D view</a>" in row
    verdict = json.loads((report / f"best/robodesign/pick_and_place/{opt}-seed{seed}.verdict.json").read_text())
    assert verdict["valid"] and f"{verdict['cost']:.6g}" in row
    # every table sits in its own scroll box
    assert page.count("<div class='tbl'><table") == page.count("<table") > 4


@pytest.mark.slow
@pytest.mark.skipif(CHROMIUM is None, reason="Debian chromium is not installed (apt-get install chromium)")
def test_report_fits_a_1400px_window(report, tmp_path):
    sync_api = pytest.importorskip("playwright.sync_api", reason="the playwright package is not installed")
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, headless=True,
                                    args=["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"])
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 900})
            page.goto((report / "index.html").as_uri())
            doc_width, window = page.evaluate("[document.documentElement.scrollWidth, window.innerWidth]")
            boxes = page.evaluate("Array.from(document.querySelectorAll('.tbl')).map("
                                  "b => [b.getBoundingClientRect().right, b.scrollWidth, b.clientWidth])")
            page.screenshot(path=str(tmp_path / "report.png"), full_page=True)
        finally:
            browser.close()
    assert window == 1400 and doc_width <= 1400  # no horizontal scrolling of the page
    assert boxes and all(right <= 1400 for right, _, _ in boxes)
