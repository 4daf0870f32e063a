"""The memory budget (issue 18): every call whose memory is a product of sizes is checked before
it allocates, and the calls that killed the interpreter with SIGABRT ("memory allocation of N
bytes failed") now end in a clean MemoryError naming the arguments, or in a correct result with
bounded memory. The former abort cases run in a child process under an address-space cap
(RLIMIT_AS) and a timeout: a signal death fails the test."""

from __future__ import annotations

import os
import re
import resource
import subprocess
import sys
import time
import tracemalloc

import numpy as np
import pytest

import motionblur as mb
from motionblur import _core
from motionblur.budget import DEFAULT_MEMORY_BUDGET, MIN_MEMORY_BUDGET, need

GiB = 1 << 30

PRELUDE = """
import numpy as np
import motionblur as mb
from motionblur import _core

def outcome(call):
    try:
        out = call()
    except (MemoryError, ValueError) as e:
        print(type(e).__name__, e)
    else:
        print("OK", out)
"""


def run_capped(body: str, cap: int = GiB, timeout: float = 120.0, env: dict | None = None) -> str:
    """Runs ``body`` in a fresh interpreter whose address space is capped at ``cap`` bytes (two
    threads, two malloc arenas, so the cap does not depend on the machine's cores); returns its
    output, after checking that it exited normally (a negative code is a signal death)."""

    def cap_memory() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))

    child_env = {**os.environ, "RAYON_NUM_THREADS": "2", "MALLOC_ARENA_MAX": "2", **(env or {})}
    proc = subprocess.run(
        [sys.executable, "-c", PRELUDE + body],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=child_env,
        preexec_fn=cap_memory,
    )
    assert proc.returncode == 0, f"the child died (code {proc.returncode}): {proc.stderr[-3000:]}"
    return proc.stdout.strip()


# ---- former aborts, each in a capped child ----

ABORTS = {
    # ContourTable of an 82k-face mesh with 65,536 directions took 5.6 GB and 48 s
    "contour_table": (
        "m = mb.Mesh(*mb.meshes.icosphere(6))\noutcome(lambda: mb.ContourTable(m, directions=65536))",
        r"MemoryError faces x directions: ContourTable needs 5\.\d\d GB .* 81920 x 65536",
    ),
    # spin_volume(..., segments=4096) of a large mesh
    "spin_volume": (
        "m = mb.Mesh(*mb.meshes.icosphere(6))\n"
        "outcome(lambda: mb.spin_volume(m, [0.0, 0.0, 1.0], 3.0, segments=4096))",
        r"MemoryError mesh edges x segments: spin_volume needs \d+\.\d\d GB .* 122880 x 4096",
    ),
    # BlurShell with 3e7 vertices
    "blur_shell": (
        "v, f = mb.meshes.icosphere(1)\noutcome(lambda: mb.BlurShell(f, n_vertices=30_000_000))",
        r"MemoryError n_vertices x subdivisions \+ 1: BlurShell needs 8\.\d\d GB .* 30000000 x 11",
    ),
    # 20,000 full-screen triangles copied into each of the 4096 tiles of a 4096x4096 frame
    "raster_bins": (
        "n = 20000\n"
        "v = np.tile([[-50.0, -50.0, 0.0], [50.0, -50.0, 0.0], [0.0, 50.0, 0.0]], (n, 1))\n"
        "f = np.arange(3 * n).reshape(-1, 3)\n"
        "cam = mb.Camera(mb.look_at((0, 0, 5), (0, 0, 0)), 0.7, 4096, 4096)\n"
        "outcome(lambda: mb.rasterize(cam, mb.Draw(v, f, (1.0, 1.0, 1.0))))",
        r"MemoryError triangles x tiles they reach: rasterize needs \d+\.\d\d GB",
    ),
    # a splat of 16 sources into the largest image sums 8 run buffers of 512 MB each
    "splat_buffers": (
        "c = np.ones((16, 4), np.float32)\np = np.zeros((16, 2, 2), np.float32)\n"
        "outcome(lambda: _core._splat_paths(c, p, 8192, 4096))",
        r"MemoryError width x height x buffers: splat_paths needs 4\.83 GB .* 8192 x 4096 x 9",
    ),
}


@pytest.mark.parametrize("case", sorted(ABORTS))
def test_former_aborts_raise_memory_error_naming_the_arguments(case):
    body, want = ABORTS[case]
    t = time.perf_counter()
    out = run_capped(body, cap=2 * GiB)
    assert re.match(want, out, flags=re.S), out
    assert "set_memory_budget" in out
    assert time.perf_counter() - t < 60


def test_a_deep_transparent_stack_renders_in_bounded_memory():
    # 2,500 full-screen transparent layers at 64x64: the lists of every fragment took 36 bytes
    # a fragment twice over (10M fragments, past the 1 GiB cap); the k-buffer keeps 32 a sample.
    body = """
n = 2500
v = np.tile([[-50.0, -50.0, 0.0], [50.0, -50.0, 0.0], [0.0, 50.0, 0.0]], (n, 1))
v[:, 2] = np.repeat(np.linspace(-1.0, 1.0, n), 3)
f = np.arange(3 * n).reshape(-1, 3)
cam = mb.Camera(mb.look_at((0, 0, 5), (0, 0, 0)), 0.7, 64, 64)
fr = mb.rasterize(cam, mb.Draw(v, f, (0.8, 0.4, 0.2, 0.002)))
print(fr.stats["approximated_samples"], *fr.rgba[32, 32])
"""
    out = run_capped(body, cap=GiB).split()
    approximated, rgba = int(out[0]), np.array(out[1:], dtype=np.float64)
    assert approximated == 64 * 64
    # one straight colour: the merged layer is exact, alpha is 1 - (1 - a)^n
    alpha = 1.0 - (1.0 - np.float32(0.002)) ** 2500
    np.testing.assert_allclose(rgba, [0.8 * alpha, 0.4 * alpha, 0.2 * alpha, alpha], atol=2e-4)


# ---- Sequence ----


@pytest.mark.parametrize("samples", [10**7, 10**9, 2**64])
def test_sequence_rejects_absurd_sample_counts_at_once(samples):
    calls = []
    t = time.perf_counter()
    with pytest.raises(ValueError, match=f"samples: must be <= {1 << 16}, got {samples}"):
        mb.Sequence(lambda t: calls.append(t) or np.zeros((4, 4, 4)), samples=samples)
    assert not calls and time.perf_counter() - t < 0.1


def test_sequence_checks_kept_images_against_the_budget_after_one_draw():
    calls = []
    seq = mb.Sequence(
        lambda t: calls.append(t) or np.zeros((512, 512, 4), np.float32), 60000, keep_images=True
    )
    with pytest.raises(MemoryError, match=r"samples x image values: Sequence needs 251\.\d\d GB"):
        seq.next()
    assert len(calls) == 1


def test_sequence_running_total_holds_the_sum_not_every_image():
    h = w = 128
    n = 64

    def render(t):
        return np.full((h, w, 4), t, np.float32)

    image_f64 = h * w * 4 * 8
    for keep, most in ((False, 6 * image_f64), (True, n * image_f64 // 2 + 6 * image_f64)):
        seq = mb.Sequence(render, n, step=0.5, keep_images=keep)
        tracemalloc.start()
        try:
            first = seq.next()
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        # all n renders in float64 would be n * image_f64 (8 MB here)
        assert peak < most, (keep, peak, most)
        np.testing.assert_allclose(first, np.full((h, w, 4), 0.5 * (n - 1) / 2), rtol=1e-6)
        np.testing.assert_allclose(seq.next(), np.full((h, w, 4), 0.5 * (n + 1) / 2), rtol=1e-6)


# ---- the budget itself ----


def test_raising_the_budget_lets_a_call_through():
    cam = mb.Camera(mb.look_at((0, 0, 5), (0, 0, 0)), 0.7, 512, 512)
    draw = mb.Draw(*mb.meshes.icosphere(2), (1.0, 0.5, 0.25))
    table_mesh = mb.Mesh(*mb.meshes.icosphere(3))
    old = mb.set_memory_budget(MIN_MEMORY_BUDGET)
    try:
        assert mb.memory_budget() == MIN_MEMORY_BUDGET
        with pytest.raises(MemoryError, match=r"width x height: rasterize needs 8\.\d\d MB .* 512 x 512"):
            mb.rasterize(cam, draw)
        with pytest.raises(MemoryError, match="faces x directions: ContourTable needs"):
            mb.ContourTable(table_mesh, directions=2048)
        assert mb.set_memory_budget(64 << 20) == MIN_MEMORY_BUDGET
        frame = mb.rasterize(cam, draw)
        assert frame.coverage.sum() > 1000
        assert len(mb.ContourTable(table_mesh, directions=2048)) == 2048
    finally:
        mb.set_memory_budget(old)
    assert mb.memory_budget() == old


def test_the_budget_setting_is_checked_and_read_from_the_environment():
    assert DEFAULT_MEMORY_BUDGET == 4 * GiB == _core.DEFAULT_MEMORY_BUDGET
    for bad, err in (
        (MIN_MEMORY_BUDGET - 1, ValueError),
        (1 << 64, ValueError),
        ("4G", TypeError),
        (True, TypeError),
    ):
        with pytest.raises(err, match="bytes"):
            mb.set_memory_budget(bad)
    out = run_capped("print(mb.memory_budget())", cap=2 * GiB, env={"MOTIONBLUR_MEMORY_BUDGET": "123456789"})
    assert out == "123456789"


def test_absurd_counts_are_value_errors():
    with pytest.raises(ValueError, match="samples: samples x image values = .* overflows 64 bits"):
        need("Sequence", ({"samples": 1 << 40, "image values": 1 << 30}, 8))
    assert need("x", ({"a": 3, "b": 5}, 8), ({"c": 1}, 1)) == 121


# ---- the k-buffer of the exact transparent pass ----


def _layers(n: int, rng) -> tuple[list[mb.Draw], np.ndarray, np.ndarray]:
    """n full-screen layers at distinct depths, random colours and alphas, in a shuffled
    submission order; their premultiplied colours sorted far to near (float32)."""
    depth = rng.permutation(n) / n * 2.0 - 1.0
    straight = rng.random((n, 3)).astype(np.float32)
    alpha = (0.01 + 0.08 * rng.random(n)).astype(np.float32)
    tri = np.array([[-50.0, -50.0, 0.0], [50.0, -50.0, 0.0], [0.0, 50.0, 0.0]])
    draws = [
        mb.Draw(tri + [0.0, 0.0, z], [[0, 1, 2]], (*c, a), object_id=i)
        for i, (z, c, a) in enumerate(zip(depth, straight, alpha))
    ]
    order = np.argsort(depth)  # far (z = -1) to near
    premul = np.concatenate([straight * alpha[:, None], alpha[:, None]], axis=1)[order]
    return draws, premul, order


def _over_far_to_near(premul: np.ndarray) -> np.ndarray:
    dst = np.zeros(4, np.float32)
    for src in premul:
        dst = src + (np.float32(1.0) - src[3]) * dst
    return dst


def test_the_exact_pass_is_exact_up_to_the_fragment_cap(rng):
    cam = mb.Camera(mb.look_at((0, 0, 5), (0, 0, 0)), 0.7, 24, 16)
    draws, premul, order = _layers(mb.raster.FRAGMENT_CAP, rng)
    for samples in (1, 2):
        fr = mb.rasterize(cam, draws, samples=samples)
        assert fr.stats["approximated_samples"] == 0
        np.testing.assert_allclose(fr.rgba[8, 12], _over_far_to_near(premul), atol=1e-6)
        assert fr.ids[8, 12] == order[-1]


def test_past_the_cap_the_nearest_are_exact_and_the_rest_merged_within_the_bound(rng):
    cap = mb.raster.FRAGMENT_CAP
    cam = mb.Camera(mb.look_at((0, 0, 5), (0, 0, 0)), 0.7, 24, 16)
    n = 3 * cap
    draws, premul, order = _layers(n, rng)
    for samples in (1, 2):
        fr = mb.rasterize(cam, draws, samples=samples)
        assert fr.stats["approximated_samples"] == 24 * 16 * samples**2
        got, want = fr.rgba[8, 12], _over_far_to_near(premul)
        assert fr.ids[8, 12] == order[-1], "the nearest layer names the pixel"
        tail, kept = premul[: n - cap], premul[n - cap :]
        through = np.prod(1.0 - kept[:, 3])
        merged_alpha = 1.0 - np.prod(1.0 - tail[:, 3])
        assert abs(got[3] - want[3]) < 1e-5, "alpha is exact"
        spread = np.ptp(tail[:, :3] / tail[:, 3:], axis=0)
        bound = through * merged_alpha * spread + 1e-5
        assert (np.abs(got[:3] - want[:3]) <= bound).all(), (got, want, bound)
        # the bound is not vacuous: the merged layer is visible through the kept ones
        assert through * merged_alpha > 0.01
    # unsorted blending holds no list: every layer is composited or dropped as it comes
    fr = mb.rasterize(cam, draws, blend="unsorted")
    assert fr.stats["approximated_samples"] == 0
