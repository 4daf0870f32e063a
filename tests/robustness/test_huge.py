"""Huge sizes and counts, each call in a child process with an address-space cap and a time
limit (a Rust allocation failure aborts the process, which must never happen): the child either
gets a clear error naming an argument or a result, and exits normally."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

pytestmark = pytest.mark.robustness

#: Address space of a child (bytes) and its time limit (s): far below the machine's, far above
#: what a call that checks its arguments first needs.
CAP = 6 << 30
TIMEOUT = 120

CHILD = """
import resource, sys
resource.setrlimit(resource.RLIMIT_AS, ({cap}, {cap}))
import numpy as np
import motionblur as mb
import motionblur.image as mbi
v, f = mb.meshes.box()
try:
    {call}
except (ValueError, TypeError, MemoryError) as exc:
    print("error", type(exc).__name__, str(exc).split(":")[0], sep="\\t")
else:
    print("ok")
"""

CASES = {
    "camera past the pixel limit": ("mb.Camera(np.eye(4), 0.7, 16384, 16384)", "width"),
    "camera side past the limit": ("mb.Camera(np.eye(4), 0.7, 2**40, 2)", "width"),
    "supersampled past the internal side": (
        "mb.rasterize(mb.Camera(mb.look_at((0,0,5),(0,0,0)), 0.7, 16384, 2), mb.Draw(v, f, (1,1,1)), samples=4)",
        "samples",
    ),
    "shell of 2**40 vertices": ("mb.BlurShell(f, n_vertices=2**40)", "faces"),
    "shell history past its budget": ("mb.BlurShell(f, subdivisions=255, n_vertices=10**8)", "subdivisions"),
    "contour table of 2**20 directions": ("mb.ContourTable(mb.Mesh(v, f), 2**20)", "directions"),
    "segments past the limit": ("mb.motion_volume(mb.Mesh(v, f), [1.0, 0, 0], segments=2**31)", "segments"),
    "face index past every vertex": ("mb.Mesh(v, np.array([[0, 1, 2**40]]))", "faces"),
    "face index past int64": ("mb.Mesh(v, np.array([[0, 1, 2**64 - 1]], dtype=np.uint64))", "faces"),
    "pyramid levels past the limit": ("mbi.pyramid_blur(np.zeros((4, 4, 4), np.float32), 10**6)", "levels"),
    "blur length past the limit": ("mbi.box_blur(np.zeros((4, 4, 4), np.float32), (1, 0), 1e30)", "length"),
    "velocity samples past the limit": (
        "mbi.velocity_blur(np.zeros((4, 4, 4), np.float32), np.zeros((4, 4, 2), np.float32), samples=2**40)",
        "samples",
    ),
    "accumulation samples of 2**64": (
        "mb.render(mb.SCENES['cube'](16, 12), 'accumulation', samples=2**64)",
        "samples",
    ),
    "colour renders past the limit": (
        "mb.render(mb.SCENES['cube'](16, 12), 'motion_volume', color_renders=10**9)",
        "color_renders",
    ),
    "a big but valid frame": (
        "mb.rasterize(mb.Camera(mb.look_at((0,0,5),(0,0,0)), 0.7, 4096, 4096), mb.Draw(v, f, (1,1,1)))",
        None,
    ),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_huge_arguments_fail_clearly_or_run_in_a_child(case):
    call, name = CASES[case]
    script = CHILD.format(cap=CAP, call=textwrap.dedent(call))
    env = dict(os.environ, RAYON_NUM_THREADS="2")
    r = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=TIMEOUT, env=env
    )
    assert r.returncode == 0, f"the child died (code {r.returncode}): {r.stderr[-2000:]}"
    out = r.stdout.strip().split("\t")
    if name is None:
        assert out == ["ok"], r.stdout
    else:
        assert out[0] == "error" and name in out[2], r.stdout
