"""The benchmark website in a real headless browser: Debian's chromium driven by Playwright.

The server is uvicorn in a thread on 127.0.0.1 (a free port). Through the page form we upload a valid and an
invalid solution, see the invalid one's violation, see the leaderboard rank the valid ones by cost, and open a
solution page whose 3-D viewer (in a sandboxed iframe) must draw something: the canvas screenshot may not be a
single colour. With ROBODESIGN_UPDATE_SCREENSHOTS=1 the leaderboard screenshot is saved as docs/img/leaderboard.png.

Playwright's own browser download is never used (``playwright install`` is not run): the system chromium is
launched by path. Skipped only when chromium or the playwright package is missing.
"""
from __future__ import annotations

import io
import os
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

CHROMIUM = next((p for p in ("/usr/bin/chromium", shutil.which("chromium") or "") if p and Path(p).exists()), None)
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="Debian chromium is not installed (apt-get install chromium)")

pytest.importorskip("fastapi", reason="the website needs fastapi")
sync_api = pytest.importorskip("playwright.sync_api", reason="the playwright package is not installed")

from PIL import Image  # noqa: E402

from robodesign.web import create_app  # noqa: E402

from test_web import BOARD, SLOW_MACHINE_VIEWER_TIMEOUT, make_seed, running_server, sol_json  # noqa: E402

ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", "--no-first-run", "--disable-dev-shm-usage",
        # WebGL without a GPU: the software rasterizer (SwiftShader), which newer Chromium only uses when asked
        "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
DOCS_IMG = Path(__file__).resolve().parents[1] / "docs" / "img"


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("browser")
    app = create_app(data_dir=tmp / "data", seed=[make_seed(tmp / "seed")], seed_builtin=False,
                     viewer_timeout=SLOW_MACHINE_VIEWER_TIMEOUT)
    with running_server(app) as url:
        yield url, tmp


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
        try:
            yield b
        finally:
            b.close()


def upload_through_form(page, url, path: Path, author: str, affiliation: str = ""):
    page.goto(f"{url}/upload")
    page.set_input_files("#file", str(path))
    page.fill("#author", author)
    if affiliation:
        page.fill("#affiliation", affiliation)
    page.click("button[type=submit]")
    page.wait_for_selector("#result")


def test_upload_rank_and_view_in_a_browser(site, browser):
    url, tmp = site
    files = {}
    for name, k, broken in (("fast.json", 1.0, False), ("broken.json", 1.0, True), ("slow.json", 1.5, False),
                            ("medium.json", 1.2, False)):
        files[name] = tmp / name
        files[name].write_text(json.dumps(sol_json(k, broken)))
    ctx = browser.new_context(viewport={"width": 1200, "height": 900})
    page = ctx.new_page()
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))

    page.goto(url)
    assert "robodesign benchmark" in page.title()
    assert page.get_by_role("link", name="toy/all", exact=True).is_visible()

    # an invalid solution: its violation is shown
    upload_through_form(page, url, files["broken.json"], "Bob Broken")
    result = page.inner_text("#result")
    assert "Invalid" in result and "joint.q" in result and "outside [-3.2, 3.2]" in result

    # a valid one: accepted with its cost, and a token
    upload_through_form(page, url, files["fast.json"], "Ada Lovelace", "Analytical Engines Ltd")
    result = page.inner_text("#result")
    assert "Valid" in result and page.inner_text("#result-cost") == "3.5"
    assert len(page.inner_text("#token")) >= 30
    page.click("#result a.mono")  # to the leaderboard
    page.wait_for_selector("#benchmark-id")
    assert page.inner_text("#benchmark-id") == BOARD
    rows = page.locator("tbody tr")
    assert rows.count() == 1 and "Ada Lovelace" in rows.nth(0).inner_text() and "3.5" in rows.nth(0).inner_text()

    # two more: the ranking updates (cost ascending), the invalid one never appears
    upload_through_form(page, url, files["slow.json"], "Grace Hopper", "COBOL Institute")
    upload_through_form(page, url, files["medium.json"], "Alan Turing", "Bletchley Park")
    page.goto(f"{url}/leaderboard/{BOARD}")
    texts = [rows.nth(i).inner_text() for i in range(rows.count())]
    assert [t.split("\t")[2] for t in texts] == ["Ada Lovelace", "Alan Turing", "Grace Hopper"]
    assert [t.split("\t")[1] for t in texts] == ["3.5", "4.2", "5.25"]
    assert "Bob Broken" not in page.content()
    page.set_viewport_size({"width": 1200, "height": 400})
    # the README's screenshot is refreshed on request only: tests never write into the checkout
    shot = DOCS_IMG / "leaderboard.png" if os.environ.get("ROBODESIGN_UPDATE_SCREENSHOTS") else tmp / "leaderboard.png"
    page.screenshot(path=str(shot), full_page=True)
    assert shot.stat().st_size > 10_000
    page.set_viewport_size({"width": 1200, "height": 900})

    # the solution page embeds the 3-D viewer, which draws
    pytest.importorskip("robodesign.viewer", reason="the 3D viewer (robodesign.viewer) is not installed")
    page.click("tbody tr >> nth=0 >> a")
    page.wait_for_selector("iframe.viewer")
    frame = page.frame_locator("iframe.viewer")
    canvas = frame.locator("canvas").first
    canvas.wait_for(state="visible", timeout=30_000)
    page.wait_for_timeout(1500)  # a few animation frames
    status = frame.locator(".error")
    assert status.count() == 0 or not status.first.is_visible(), status.first.inner_text()
    png = canvas.screenshot()
    (tmp / "viewer.png").write_bytes(png)
    img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=float)
    assert img.shape[0] > 100 and img.shape[1] > 100
    colours = len(np.unique(img.reshape(-1, 3), axis=0))
    assert img.var(axis=(0, 1)).sum() > 50 and colours > 20, (img.var(axis=(0, 1)), colours)
    assert not errors, errors
    ctx.close()
