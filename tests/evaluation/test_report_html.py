"""The report as a static HTML page, opened from disk in Debian's headless Chromium (through
playwright, with the system's browser): every picture loads, nothing is logged to the console,
the screenshot is not blank, and the viewer switches images."""

from __future__ import annotations

import io
import shutil

import numpy as np
import pytest
from PIL import Image

from motionblur._optional import require
from motionblur.evaluation import bench

CHROMIUM = "/usr/bin/chromium-headless-shell"


@pytest.mark.mitsuba
@pytest.mark.chromium
def test_the_html_report_renders_in_headless_chromium(tmp_path):
    sweeps = {
        "accumulation": [{"samples": 1}, {"samples": 8}],
        "motion_volume": [{"segments": 1, "filter": "box"}],
    }
    res = bench.run(tmp_path, scenes=["cube", "torus_turn"], width=48, height=36, times=4, spp=1, repeat=1,
                    methods=[*sweeps, "auto"], sweeps=sweeps, flip=False, pyrender_peer=False,
                    limit_samples=32, log=lambda *a: None)  # fmt: skip
    page = res["paths"]["html"]
    md = res["paths"]["md"].read_text()
    assert "## auto against the Pareto front" in md and "| torus_turn | " in md.split("## auto against")[1]
    # the plan column names the render auto kept (it read "static" for every scene once auto's
    # plan stopped listing per-object choices)
    row = next(x for x in md.split("## auto against")[1].splitlines() if x.startswith("| torus_turn |"))
    assert row.split("|")[2].strip().startswith(("accumulation samples=", "analytic")), row
    assert set(res["auto"]) == {"cube", "torus_turn"} and all(
        x["meets"] in (True, False) for x in res["auto"].values()
    )
    # one folder: it still works when moved elsewhere
    moved = shutil.copytree(page.parent, tmp_path / "moved")
    assert shutil.which(CHROMIUM), (
        f"{CHROMIUM} is missing: apt-get install chromium-headless-shell (make sysdeps)"
    )
    sync_playwright = require("playwright.sync_api", "the HTML report test").sync_playwright
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        tab = browser.new_page(viewport={"width": 1200, "height": 900})
        problems = []
        tab.on(
            "console",
            lambda m: problems.append(f"{m.type}: {m.text}") if m.type in ("error", "warning") else None,
        )
        tab.on("pageerror", lambda e: problems.append(f"page error: {e}"))
        tab.on("requestfailed", lambda r: problems.append(f"failed: {r.url}"))
        tab.goto((moved / "index.html").as_uri())
        tab.wait_for_selector("body[data-ready='1']", timeout=30_000)
        assert tab.evaluate("document.body.dataset.failed") == "0"
        sizes = tab.evaluate("[...document.images].map(i => [i.complete, i.naturalWidth])")
        assert sizes and all(done and w > 0 for done, w in sizes), sizes
        assert tab.locator("section").count() == 2 and tab.locator("section#torus_turn img.plot").count() == 1
        shot = np.asarray(Image.open(io.BytesIO(tab.screenshot(full_page=True))).convert("L"), np.float64)
        # the viewer: clicking a method shows its image and its difference
        section = tab.locator("section#cube")
        before = section.locator(".view img").first.get_attribute("src")
        section.locator(".tabs button", has_text="motion_volume").click()
        after = section.locator(".view img").first.get_attribute("src")
        caption = section.locator("figcaption").first.text_content()
        section.locator(".tabs button[data-ref='limit']").click()
        diff = section.locator(".view img").nth(1).get_attribute("src")
        browser.close()
    assert not problems, problems
    assert shot.std() > 20 and (shot < 80).mean() > 0.01 and (shot > 200).mean() > 0.2  # text, plots, images
    assert before != after and "motion_volume" in after and "motion_volume" in caption and "RMSE" in caption
    assert diff.endswith("_diff_limit.png")
