"""Writes the pictures of the README and the method pages (``docs/img/*.png``, checked in so that
GitHub shows them): each method on a built-in scene beside the unblurred frame and the exact
time integral (``motionblur.exact``), each labelled with its RMSE against the exact frame.

    PYTHONPATH=python python docs/make_figures.py        # from the repository's root, ~1 minute

The pictures are deterministic (the same bits on every run and thread count).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

import motionblur as mb
from motionblur.evaluation.figures import sheet

OUT = Path(__file__).resolve().parent / "img"
W, H = 200, 150

#: method -> (built-in scene, options): a scene each method applies to, at its defaults.
SHOWN = {
    "accumulation": ("curved", {"samples": 16}),
    "analytic": ("curved", {}),
    "motion_volume": ("cube", {}),
    "blur_shell": ("bending_arm", {}),
    "velocity": ("airplane", {}),
    "opaque_image": ("bending_arm", {}),
    "camera_velocity": ("pan", {}),
    "auto": ("curved", {"tolerance": 0.004}),
}


def _rmse(a, b) -> float:
    return float(np.sqrt(np.mean(np.square(np.asarray(a, np.float64) - b))))


def _frames(name: str):
    scene = mb.SCENES[name](W, H)
    exact = mb.exact(scene).rgba
    sharp = mb.render(scene, "accumulation", samples=1, error_estimate=False).rgba
    return scene, exact, sharp


def method_figure(method: str, scene_name: str, options: dict) -> Path:
    scene, exact, sharp = _frames(scene_name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a PoorBlurWarning is the page's subject, not news here
        frame = mb.render(scene, method, **options)
    none, err = _rmse(sharp, exact), _rmse(frame.rgba, exact)
    opts = ", ".join(f"{k}={v}" for k, v in options.items()) or "defaults"
    tiles = [
        (f"no blur (mid-shutter)\n{scene_name}\nRMSE {none:.4f}", sharp),
        (f"{method}\n{opts}\nRMSE {err:.4f} ({err / none:.2f}x no blur)", frame.rgba),
        ("exact\nmotionblur.exact\n(the reference)", exact),
    ]
    path = OUT / f"{method}.png"
    sheet(tiles, path, columns=3)
    return path


def hero() -> Path:
    scene, exact, sharp = _frames("curved")
    tiles = [("no blur\n\n", sharp)]
    for method, opts in (
        ("accumulation", {"samples": 8}),
        ("motion_volume", {}),
        ("auto", {"tolerance": 0.004}),
    ):
        frame = mb.render(scene, method, **opts)
        err = _rmse(frame.rgba, exact)
        label = ", ".join(f"{k}={v}" for k, v in opts.items()) or "defaults"
        tiles.append((f"{method}\n{label}\nRMSE {err:.4f} against exact", frame.rgba))
    tiles.append(("exact\nthe time integral\n", exact))
    path = OUT / "motionblur.png"
    sheet(tiles, path, columns=5)
    return path


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    print(hero())
    for method, (scene, options) in SHOWN.items():
        print(method_figure(method, scene, options))


if __name__ == "__main__":
    main()
