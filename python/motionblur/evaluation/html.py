"""The report as a static HTML page: one folder, opened from disk in a browser, no server.

``<out>/html/index.html`` with its pictures under ``<out>/html/img/``: per scene, the Pareto
plot (error against Mitsuba and against the own limit, the fronts annotated) and an image
viewer: the two references, ``auto`` and each method's most accurate option set within the
matched time (`report.matched`), any one of them shown large beside its difference
from the chosen reference (absolute difference of premultiplied RGBA, averaged over the
channels, times `GAIN`, black -> red -> yellow -> white). The page's data is one JSON
object in the page; its script builds the viewer, and it marks ``<body data-ready="1">`` once
every picture has loaded (``data-failed`` counts pictures that did not) so a test can wait for it.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np

from .._optional import require
from ..raster import Frame
from .report import limit_label, matched

__all__ = ["write", "GAIN"]

#: Scale of the difference view: an error of 1 / GAIN is drawn at full intensity.
GAIN = 10.0


def _png(rgba: np.ndarray, path: Path) -> None:
    h, w = rgba.shape[:2]
    Frame(
        np.asarray(rgba, np.float32), np.zeros((h, w)), np.zeros((h, w), np.int32), np.zeros((h, w, 2))
    ).save_png(path)


def _diff_png(a: np.ndarray, b: np.ndarray, path: Path) -> None:
    image = require("PIL.Image", "the HTML report")
    d = np.clip(np.abs(np.asarray(a, np.float64) - np.asarray(b, np.float64)).mean(axis=-1) * GAIN, 0.0, 1.0)
    rgb = np.stack([np.clip(3 * d, 0, 1), np.clip(3 * d - 1, 0, 1), np.clip(3 * d - 2, 0, 1)], -1)
    image.fromarray(np.round(rgb * 255).astype(np.uint8), mode="RGB").save(path)


_PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>motionblur: speed against error</title>
<style>
body{font-family:sans-serif;margin:16px;background:#fafafa;color:#222}
h2{margin-top:28px;border-top:1px solid #ccc;padding-top:12px}
.plot{max-width:100%;border:1px solid #ddd;background:#fff}
.tabs button{margin:2px;padding:4px 8px;border:1px solid #999;background:#fff;cursor:pointer;font-size:12px}
.tabs button.on{background:#234;color:#fff}
.view{display:flex;gap:12px;flex-wrap:wrap;margin-top:8px}
.view figure{margin:0}
.view img{image-rendering:pixelated;width:480px;background:#000;border:1px solid #444}
figcaption{font-size:12px;margin-top:4px;white-space:pre-line}
nav a{margin-right:10px;font-size:13px}
</style></head>
<body data-ready="0" data-failed="0">
<h1>motionblur: speed against error</h1>
<p id="settings"></p>
<nav id="nav"></nav>
<div id="scenes"></div>
<script id="data" type="application/json">__DATA__</script>
<script>
"use strict";
const data = JSON.parse(document.getElementById("data").textContent);
document.getElementById("settings").textContent = data.settings;
let pending = 0, failed = 0;
function track(img) {
  pending += 1;
  const done = (ok) => { pending -= 1; if (!ok) { failed += 1; document.body.dataset.failed = String(failed); }
    if (pending === 0) document.body.dataset.ready = "1"; };
  img.addEventListener("load", () => done(true), {once: true});
  img.addEventListener("error", () => done(false), {once: true});
}
function el(tag, attrs, text) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}
const nav = document.getElementById("nav"), root = document.getElementById("scenes");
for (const sc of data.scenes) {
  nav.appendChild(el("a", {href: "#" + sc.name}, sc.name));
  const sec = el("section", {id: sc.name});
  sec.appendChild(el("h2", {}, sc.name));
  const plot = el("img", {class: "plot", src: sc.pareto, alt: "Pareto plot of " + sc.name});
  track(plot); sec.appendChild(plot);
  sec.appendChild(el("p", {}, "Matched time: " + sc.matched_ms.toFixed(2) + " ms (each method's most accurate option set within it)."));
  const refTabs = el("div", {class: "tabs"}), tabs = el("div", {class: "tabs"});
  refTabs.appendChild(el("span", {}, "difference against: "));
  tabs.appendChild(el("span", {}, "image: "));
  const view = el("div", {class: "view"});
  const main = el("img", {alt: "image"}), diff = el("img", {alt: "difference"});
  const capMain = el("figcaption"), capDiff = el("figcaption");
  const f1 = el("figure"), f2 = el("figure");
  f1.append(main, capMain); f2.append(diff, capDiff); view.append(f1, f2);
  let cur = 0, ref = "mitsuba";
  function show() {
    const im = sc.images[cur];
    main.src = im.src; capMain.textContent = im.label;
    diff.src = im.diff[ref]; capDiff.textContent = "|image - " + ref + "| x " + data.gain;
    for (const [i, b] of [...tabs.querySelectorAll("button")].entries()) b.className = i === cur ? "on" : "";
    for (const b of refTabs.querySelectorAll("button")) b.className = b.dataset.ref === ref ? "on" : "";
  }
  for (const r of ["mitsuba", "limit"]) {
    const b = el("button", {"data-ref": r}, r === "mitsuba" ? "Mitsuba" : "own limit");
    b.addEventListener("click", () => { ref = r; show(); }); refTabs.appendChild(b);
  }
  sc.images.forEach((im, i) => {
    const b = el("button", {}, im.title); b.addEventListener("click", () => { cur = i; show(); }); tabs.appendChild(b);
    for (const src of [im.src, im.diff.mitsuba, im.diff.limit]) { const pre = new Image(); track(pre); pre.src = src; }
  });
  sec.append(refTabs, tabs, view);
  root.appendChild(sec);
  show();
}
if (pending === 0) document.body.dataset.ready = "1";
</script>
</body></html>
"""


def write(out, names, rows, paths: dict, references: dict, frames: dict, settings: dict) -> Path:
    """Write ``<out>/html/index.html`` and its pictures (see the module docs); ``paths`` are
    the report's files (``pareto_<scene>``), ``references`` {scene: {"mitsuba", "limit": rgba}},
    ``frames`` {(scene, method, options): rgba}. Returns the page's path."""
    folder = Path(out) / "html"
    img = folder / "img"
    img.mkdir(parents=True, exist_ok=True)
    scenes = []
    for name in names:
        refs = references[name]
        shutil.copyfile(paths[f"pareto_{name}"], img / f"pareto_{name}.png")
        t, picks = matched([r for r in rows if r["scene"] == name])
        entries = [
            (
                "mitsuba",
                "reference: Mitsuba",
                refs["mitsuba"],
                f"Mitsuba, K = {settings['times']} x {settings['spp']} spp",
            )
        ]
        entries.append(("limit", "reference: own limit", refs["limit"], limit_label(settings)))
        for r in picks:
            rgba = frames.get((name, r["method"], r["options"]))
            if rgba is not None:
                label = (f"{r['method']} {r['options']}\n{r['ms']:.2f} ms, RMSE {r['rmse']:.5f} against Mitsuba, "
                         f"{r['rmse_limit']:.5f} against the own limit")  # fmt: skip
                entries.append((f"{r['method']}", r["method"], rgba, label))
        images = []
        for i, (key, title, rgba, label) in enumerate(entries):
            stem = f"{name}_{i:02d}_{key}"
            _png(rgba, img / f"{stem}.png")
            diff = {}
            for ref in ("mitsuba", "limit"):
                _diff_png(rgba, refs[ref], img / f"{stem}_diff_{ref}.png")
                diff[ref] = f"img/{stem}_diff_{ref}.png"
            images.append({"title": title, "label": label, "src": f"img/{stem}.png", "diff": diff})
        scenes.append({"name": name, "pareto": f"img/pareto_{name}.png", "matched_ms": t, "images": images})
    info = (
        f"{settings['width']}x{settings['height']}, methods at aa = {settings['aa']}; references: Mitsuba "
        f"{settings['variant']} (K = {settings['times']} x {settings['spp']} spp) and each method's own limit "
        f"({limit_label(settings)}); run: {settings.get('runner', 'serial')}. Each image has two RMSEs "
        "(root mean square error over premultiplied linear RGBA): against Mitsuba, an independent path "
        "tracer with its own sampling noise and shading, then against the own limit named above, which "
        "shares this library's rasterization and shading and so measures the motion blur's error alone."
    )
    blob = json.dumps({"settings": info, "gain": GAIN, "scenes": scenes}).replace("</", "<\\/")
    page = folder / "index.html"
    page.write_text(_PAGE.replace("__DATA__", blob))
    return page
