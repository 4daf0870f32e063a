"""The report's pictures: one colour per method in every Pareto plot, the front's points
labelled, and a labelled side-by-side sheet per scene with the images as rendered."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

import motionblur as mb
from motionblur.evaluation import bench, figures


def _rows(methods):
    rows = []
    for i, m in enumerate(methods):
        rows += [
            {"method": m, "options": f"n={k}", "ms": 1.0 + i + k, "rmse": 0.1 / (1 + k + i)} for k in range(3)
        ]
    return rows


def test_a_method_keeps_its_colour_across_plots_and_the_front_is_labelled(tmp_path):
    a = _rows(["accumulation", "motion_volume", "opaque_image"])
    b = _rows(["camera_velocity", "motion_volume", "blur_shell"])
    fa = figures.pareto_plot("a", a, [True] * len(a), tmp_path / "a.png")
    front = [r["options"] == "n=2" for r in b]
    fb = figures.pareto_plot("b", b, front, tmp_path / "b.png")
    assert fa["colors"]["motion_volume"] == fb["colors"]["motion_volume"]
    every = figures.method_colors()
    assert set(mb.METHODS) <= set(every) and len(set(every.values())) == len(every)  # distinct colours
    assert all(fb["colors"][m] == every[m] for m in fb["colors"])
    assert sorted(fb["labels"]) == sorted(f"{r['method']} n=2" for r in b if r["options"] == "n=2")
    assert Image.open(tmp_path / "b.png").size[0] > 600


def test_the_sheet_shows_each_image_with_its_label(tmp_path):
    frames = [mb.render(mb.SCENES["cube"](40, 30), "accumulation", samples=n) for n in (1, 4, 16)]
    tiles = [
        (f"accumulation\nsamples={n}\n{f.stats['ms']:.2f} ms   RMSE 0.00000", f.rgba)
        for n, f in zip((1, 4, 16), frames)
    ]
    labels = figures.sheet(tiles, tmp_path / "s.png", columns=2)
    assert labels == [t[0] for t in tiles]
    img = np.asarray(Image.open(tmp_path / "s.png").convert("RGB"))
    cell_h = 30 + figures.TILE_LABEL_LINES * 13 + 8
    assert img.shape == (2 * cell_h, 2 * (40 + 4) + 4, 3)
    for k, f in enumerate(frames):
        y, x = (k // 2) * cell_h + 4, (k % 2) * 44 + 4
        srgb = f.to_srgb8()
        opaque = srgb[..., 3] == 255
        np.testing.assert_array_equal(img[y : y + 30, x : x + 40][opaque], srgb[..., :3][opaque])
        label = img[y + 30 : y + cell_h - 4, x : x + 40]
        assert (label < 100).any() and (label == 255).any(), "no text under the tile"
    with pytest.raises(ValueError, match="tiles: tile 1 is"):
        figures.sheet([("a", frames[0].rgba), ("b", np.zeros((5, 5, 4)))], tmp_path / "x.png")


@pytest.mark.mitsuba
def test_a_run_with_images_writes_a_sheet_per_scene(tmp_path):
    sweeps = {
        "accumulation": [{"samples": 1}, {"samples": 4}],
        "motion_volume": [{"segments": 1, "filter": "box"}],
    }
    res = bench.run(tmp_path, scenes=["cube"], width=32, height=24, times=4, spp=2, repeat=1, methods=list(sweeps),
                    sweeps=sweeps, flip=False, pyrender_peer=False, save_images=True, log=lambda *a: None)  # fmt: skip
    sheet = Image.open(res["paths"]["sheet_cube"])
    cell_h = 24 + figures.TILE_LABEL_LINES * 13 + 8
    assert sheet.size == (4 * (32 + 4) + 4, cell_h)  # the reference and three runs in one row
