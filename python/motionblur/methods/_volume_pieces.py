"""Pieces of the shutter for motion volumes: where one volume cannot stand for the motion.

A motion volume joins the object at shutter open and close along one face split (paper section
3.3): it stands for a motion that is nearly a straight translation. The paper itself names where
it fails (section 4.3: objects that turn quickly), and three failures were measured here: a box
that moves 2 units while turning 1.4-1.57 rad gave an empty frame, curved multi-key paths and
hand-held cameras gave frames worse than no blur (one volume over a path that bends folds over
itself, and ``segments=1`` follows the chord of the whole path), and long translations seen in
perspective gave up to 2.5 times the exact coverage (the coverage model's hulls are taken at
eight instants and the image of the object changes in between).

So the shutter is cut into pieces, each short enough for one volume, and the frame is the sum of
the pieces' frames weighted by the shutter filter's weight of each piece: the time-averaged image
is linear in time, ``I = sum_i W_i I_i`` with ``I_i`` the average over piece ``i``, and each piece's
frame (its volumes over the static scene) is such an average. Compositing the volumes of several
pieces with *over* instead would count a pixel covered in two pieces as ``a + b - ab``.

A piece must hold, for every object with apparent motion (the camera's folded in, section 3.1),
on a fine grid of the shutter (`GRID` steps and every keyframe time):

- the rotation of the object's placement turns at most `MAX_TURN` radians (the sum of the
  grid steps' angles), and its arc (the angle times the farthest vertex's distance from the
  centroid) is at most `DOMINANCE` times the centroid's displacement over the piece (the
  paper's "rotates slowly compared to its translation") or below `ARC_PX` pixels (an
  object that turns in place is drawn about as a sample per piece);
- the vertex centroid stays within `MAX_BEND` object radii of the chord of the piece
  followed at constant speed (the volume follows the chord with ``segments=1``, and its alphas
  take the time spent along it as uniform: a path that bends, or slows down at a keyframe, is
  cut there);
- the centroid's path crosses at most `MAX_SWEEP` radians of the view seen from the
  camera (perspective: the image of the object changes along a long path).

``plan`` cuts the shutter greedily, each piece as long as the grid allows; more than
`MAX_PIECES` pieces raise ``ValueError`` naming ``pieces`` and the exact methods. The
constants were tuned on the turning-box, long-translation and seeded random cases of
``tests/methods/test_motion_volume_exact.py`` (tuning seeds only).
"""

from __future__ import annotations

import numpy as np

from ..scene import Motion, Object, Scene

#: Largest rotation (radians) of an object's apparent placement within a piece.
MAX_TURN = 0.35
#: A turn counts only when its arc (farthest vertex from the centroid) exceeds DOMINANCE times the
#: centroid's displacement over the piece and ARC_PX pixels: the first of these that needs at
#: most MAX_PIECES pieces (a piece of a turn in place draws the object about where it is at the
#: piece's end, so the arc is the spacing of samples; 2 px: a face-on propeller 0.16 of the sharp
#: frame's error, 4 px: 0.34, where 2 px would need too many pieces).
DOMINANCE = 2.0
ARC_PX = (2.0, 4.0)
#: Largest distance of the vertex centroid from the piece's chord followed at constant speed, in
#: object radii.
MAX_BEND = 0.03
#: Largest angle (radians) the centroid's path crosses, seen from the camera, within a piece.
MAX_SWEEP = 0.6
#: Most pieces a frame is cut into.
MAX_PIECES = 64
#: Steps of the fine grid the criteria are tested on (plus every keyframe time).
GRID = 256
#: Uniform samples of the apparent motion per piece (plus the keyframe times within it).
PIECE_KEYS = 8


def apparent_at(scene: Scene, obj: Object, times: np.ndarray) -> np.ndarray:
    """(N,4,4) placements of the rigid ``obj`` at ``times`` as the camera at the reference time
    sees them: ``P(t_r) inv(P(t)) O(t)`` (paper section 3.1)."""
    times = np.asarray(times, np.float64)
    if obj.is_moving:
        own = obj.motion.transforms_at(times)
    else:
        own = np.broadcast_to(obj.transform_at(0.0), (len(times), 4, 4))
    if scene.camera_moves:
        ref = scene.camera_pose_at(scene.reference_t)
        own = ref @ np.linalg.inv(scene.camera_poses_at(times)) @ own
    return np.ascontiguousarray(own)


def _key_times(scene: Scene, objects) -> np.ndarray:
    ts = [np.asarray(o.motion.times) for o in objects if o.is_moving]
    if scene.camera_moves:
        ts.append(np.asarray(scene.camera_motion.times))
    return np.concatenate(ts) if ts else np.zeros(0)


def _grid(scene: Scene, objects, extra=()) -> np.ndarray:
    t = np.concatenate(
        [np.linspace(0.0, 1.0, GRID + 1), _key_times(scene, objects), np.asarray(extra, float)]
    )
    t = np.unique(np.clip(t, 0.0, 1.0))
    # merge times closer than a millionth of the shutter (rounding of the same keyframe time)
    keep = np.concatenate([[True], np.diff(t) > 1e-9])
    keep[-1] = True
    t = t[keep]
    if len(t) > 2 and t[-1] - t[-2] <= 1e-9:
        t = np.delete(t, -2)
    return t


class _Track:
    """One object's apparent motion on the grid: cumulative turn, centroid, radius."""

    def __init__(self, scene: Scene, obj: Object, times: np.ndarray, turns: bool):
        keys = apparent_at(scene, obj, times)
        m3 = keys[:, :3, :3]
        scale = np.cbrt(np.linalg.det(m3))
        v = obj.mesh.vertices
        centre = v.mean(axis=0)
        self.radius = float(np.sqrt(((v - centre) ** 2).sum(axis=1).max()) * abs(scale[0]))
        self.centre = m3 @ centre + keys[:, :3, 3]
        self.times = times
        if turns:
            rots = m3 / scale[:, None, None]
            rel = rots[1:] @ np.transpose(rots[:-1], (0, 2, 1))
            c = np.clip((np.trace(rel, axis1=1, axis2=2) - 1.0) * 0.5, -1.0, 1.0)
            self.turn = np.concatenate([[0.0], np.cumsum(np.arccos(c))])
        else:
            self.turn = np.zeros(len(times))

    def measures(self, i: int, js: np.ndarray, view):
        """(turn, bend in radii, sweep in radians) of the pieces from grid index ``i`` to each
        of ``js`` (> i); a turn that the piece's translation dominates, or whose arc is below
        ``arc_px`` pixels, counts as 0. ``view``: (eye, forward, focal length in pixels, arc_px)."""
        eye, forward, focal, arc_px = view
        turn = self.turn[js] - self.turn[i]
        c = self.centre
        a = c[i]
        ends = c[js] - a  # (J,3)
        arc = turn * self.radius
        depth = np.maximum(np.minimum((c[js] - eye) @ forward, (a - eye) @ forward), 1e-9)
        slow = (arc <= DOMINANCE * np.linalg.norm(ends, axis=1)) | (arc * focal / depth <= arc_px)
        turn = np.where(slow & (turn <= MAX_TURN), 0.0, turn)
        # the centroid at the inner grid times k against the chord followed at constant speed
        k = np.arange(i + 1, js.max() + 1)
        t = self.times
        u = (t[k][:, None] - t[i]) / (t[js] - t[i])[None, :]  # (K,J)
        off = (c[k] - a)[:, None, :] - u[..., None] * ends[None, :, :]  # (K,J,3)
        dist = np.where(k[:, None] < js[None, :], np.linalg.norm(off, axis=2), 0.0)
        bend = dist.max(axis=0) / max(self.radius, 1e-300)
        u, w = a - eye, c[js] - eye
        cos = (w @ u) / np.maximum(np.linalg.norm(w, axis=1) * np.linalg.norm(u), 1e-300)
        sweep = np.arccos(np.clip(cos, -1.0, 1.0))
        return turn, bend, sweep


def _fits(tracks, i: int, js: np.ndarray, view) -> np.ndarray:
    ok = np.ones(len(js), bool)
    for tr in tracks:
        turn, bend, sweep = tr.measures(i, js, view)
        ok &= (turn == 0.0) & (bend <= MAX_BEND) & (sweep <= MAX_SWEEP)
    return ok


def _worst(tracks, i: int, j: int, view) -> str:
    """What the piece from grid index ``i`` to ``j`` exceeds, for the error messages."""
    out = []
    for k, tr in tracks:
        turn, bend, sweep = (float(x[0]) for x in tr.measures(i, np.array([j]), view))
        if turn > MAX_TURN:
            out.append(f"object {k} turns {turn:.2f} rad (at most {MAX_TURN} per piece)")
        elif turn > 0.0:
            eye, forward, focal, arc_px = view
            depth = max(float((tr.centre[j] - eye) @ forward), 1e-9)
            out.append(
                f"object {k} turns {turn:.2f} rad more than it moves, its farthest point "
                f"{turn * tr.radius * focal / depth:.1f} pixels (at most {arc_px:g} per piece)"
            )
        if bend > MAX_BEND:
            out.append(f"object {k}'s path bends {bend:.2f} object radii off its chord (at most {MAX_BEND})")
        if sweep > MAX_SWEEP:
            out.append(f"object {k}'s path crosses {sweep:.2f} rad of the view (at most {MAX_SWEEP})")
    return "; ".join(out)


def _view(scene: Scene, arc_px: float):
    """(eye, forward, focal length in pixels, arc_px) of the camera at the reference time."""
    cam = scene.camera_at(scene.reference_t)
    pose = cam.pose
    return pose[:3, 3], -pose[:3, 2], cam.height / (2.0 * np.tan(0.5 * cam.yfov)), arc_px


def _tracks(scene: Scene, spun, times):
    """(index, _Track) of every object with apparent motion; ``spun``: indices drawn as spin
    volumes (their rotation is the spin volume's, not a piece's)."""
    out = []
    for k, obj in enumerate(scene.objects):
        if not obj.is_moving and not scene.camera_moves:
            continue
        out.append((k, _Track(scene, obj, times, turns=k not in spun)))
    return out


def plan(scene: Scene, spun=frozenset()) -> np.ndarray:
    """Boundaries (P+1,) of the fewest greedy pieces of the shutter that each hold the criteria
    of the module docs for every object, with the arc of a turn in place limited to the first of
    ARC_PX that needs at most MAX_PIECES pieces; ValueError naming ``pieces`` past MAX_PIECES."""
    times = _grid(scene, scene.objects)
    tracks = _tracks(scene, spun, times)
    if not tracks:
        return np.array([0.0, 1.0])
    for k, arc_px in enumerate(ARC_PX):
        try:
            return _greedy(times, tracks, _view(scene, arc_px))
        except ValueError:
            if k == len(ARC_PX) - 1:
                raise
    raise AssertionError("unreachable")


def _greedy(times, tracks, view) -> np.ndarray:
    plain = [t for _, t in tracks]
    n = len(times) - 1
    bounds = [0]
    i = 0
    while i < n:
        # the longest piece whose every shorter prefix fits too, among candidate ends doubling
        # in reach until one fails (the test of K ends costs K^2)
        reach = 16
        while True:
            js = np.arange(i + 1, min(n, i + reach) + 1)
            bad = np.flatnonzero(~_fits(plain, i, js, view))
            if len(bad) or js[-1] == n:
                break
            reach *= 2
        if len(bad) and bad[0] == 0:
            raise ValueError(
                f"pieces: within {times[i + 1] - times[i]:.3g} of the shutter from t = {times[i]:.3g} "
                f"{_worst(tracks, i, i + 1, view)}: too fast for motion volumes (at most {MAX_PIECES} "
                "pieces of the shutter); use render(scene, 'analytic') or render(scene, 'accumulation')"
            )
        j = int(js[bad[0] - 1]) if len(bad) else n
        bounds.append(j)
        if len(bounds) - 1 > MAX_PIECES:
            raise ValueError(
                f"pieces: this motion needs more than {MAX_PIECES} pieces of the shutter for motion "
                f"volumes (from t = {times[i]:.3g} to {times[min(n, j + 1)]:.3g}: "
                f"{_worst(tracks, i, min(n, j + 1), view)}); a motion volume cannot represent it: use "
                "render(scene, 'analytic') or render(scene, 'accumulation')"
            )
        i = j
    return times[bounds]


def check_equal(scene: Scene, pieces: int, spun=frozenset()) -> np.ndarray:
    """Boundaries of ``pieces`` equal pieces, or ValueError naming ``pieces`` when one of them
    breaks the criteria of the module docs."""
    bounds = np.linspace(0.0, 1.0, pieces + 1)
    times = _grid(scene, scene.objects, bounds)
    tracks = _tracks(scene, spun, times)
    if not tracks:
        return bounds
    view = _view(scene, ARC_PX[-1])
    idx = np.searchsorted(times, bounds)
    idx = np.clip(idx, 0, len(times) - 1)
    for a, b in zip(idx[:-1], idx[1:]):
        if b <= a:
            continue
        if not _fits([t for _, t in tracks], int(a), np.array([int(b)]), view)[0]:
            raise ValueError(
                f"pieces: with {pieces} piece(s) of the shutter {_worst(tracks, int(a), int(b), view)}; "
                "one motion volume per piece cannot represent that: pass pieces='auto' (enough pieces "
                "are chosen), or use render(scene, 'analytic') or render(scene, 'accumulation')"
            )
    return bounds


class PieceScene(Scene):
    """The scene over the piece ``[a, b]`` of the shutter, as a shutter of its own (time ``u`` in
    [0, 1] is the original ``a + (b - a) u``): each moving object moves by its own motion over
    ``[a, b]`` (sampled at PIECE_KEYS + 1 times and the keyframe times within, exact between
    keyframes: rigid keyframes interpolate the same), static objects are the original ones, the
    camera poses are the original scene's (exactly, [`camera_pose_at`][motionblur.scene.Scene.camera_pose_at]; ``camera_motion``
    samples them like the objects, for the tests that read its keyframes), the shutter is a
    box (the methods take the filter's weight of the piece themselves) and the reference time is
    the original one in piece time, ``(t_r - a) / (b - a)``, which may lie outside [0, 1]: the
    volumes of every piece are seen by the same camera and folded to the same pose."""

    def __init__(self, scene: Scene, a: float, b: float):
        inner = _key_times(scene, scene.objects)
        t = np.unique(np.concatenate([np.linspace(a, b, PIECE_KEYS + 1), inner[(inner > a) & (inner < b)]]))
        u = (t - a) / (b - a)
        keep = np.concatenate([[True], np.diff(u) > 1e-9])
        keep[-1] = True
        t, u = t[keep], u[keep]
        if len(u) > 2 and u[-1] - u[-2] <= 1e-9:
            t, u = np.delete(t, -2), np.delete(u, -2)
        u[0], u[-1] = 0.0, 1.0
        objects = [
            Object(o.mesh, o.color, o.shading, motion=Motion(u, o.motion.transforms_at(t)), name=o.name)
            if o.is_moving
            else o
            for o in scene.objects
        ]
        camera_motion = None
        if scene.camera_moves:
            base = np.linalg.inv(scene.camera.pose)
            camera_motion = Motion(u, scene.camera_poses_at(t) @ base)
        super().__init__(
            objects, scene.camera, scene.lights, camera_motion, "box", scene.background, 1.0, scene.ambient
        )
        self.whole, self.piece = scene, (a, b)
        self.reference_t = (scene.reference_t - a) / (b - a)
        self.reference_time = self.reference_t

    def _time(self, u):
        a, b = self.piece
        return a + (b - a) * np.asarray(u, np.float64)

    def camera_pose_at(self, t: float) -> np.ndarray:
        return self.whole.camera_pose_at(float(self._time(t)))

    def camera_poses_at(self, times) -> np.ndarray:
        return self.whole.camera_poses_at(self._time(times))


def piece_scene(scene: Scene, a: float, b: float) -> PieceScene:
    """The scene over the piece ``[a, b]`` of the shutter (see `PieceScene`)."""
    return PieceScene(scene, a, b)
