"""A numpy twin of the keyframe engine (``src/motion/``): the same splitting of a similarity
(determinant, cube root, Shepperd's quaternion) and the same interpolation (translation and
scale lerped, rotation slerped on the shorter arc, normalised lerp only for quaternions within
1e-12 in cosine), in plain numpy operations."""

from __future__ import annotations

import math

import numpy as np

NEARLY_EQUAL = 1.0 - 1e-12


def quaternion(r: np.ndarray) -> np.ndarray:
    """(4,) unit quaternion (w, x, y, z) of a 3x3 rotation (Shepperd's method)."""
    tr = np.trace(r)
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2]) * 2
        q = [(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s]
    elif r[1, 1] > r[2, 2]:
        s = math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2]) * 2
        q = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s]
    else:
        s = math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1]) * 2
        q = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s]
    q = np.asarray(q)
    return q / np.linalg.norm(q)


def rotation_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def slerp(q0: np.ndarray, q1: np.ndarray, u: float) -> np.ndarray:
    d = float(q0 @ q1)
    if d < 0.0:
        q1, d = -q1, -d
    if d > NEARLY_EQUAL:
        q = q0 + u * (q1 - q0)
        return q / np.linalg.norm(q)
    theta = math.acos(min(1.0, d))
    return (math.sin((1 - u) * theta) * q0 + math.sin(u * theta) * q1) / math.sin(theta)


def split(m: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """(translation, quaternion, scale) of a 4x4 similarity."""
    s = np.linalg.det(m[:3, :3]) ** (1.0 / 3.0)
    return m[:3, 3].copy(), quaternion(m[:3, :3] / s), s


def transform_at(times: np.ndarray, mats: np.ndarray, t: float) -> np.ndarray:
    """(4,4) transform at ``t`` of rigid keyframes ``mats`` (K,4,4) at ``times`` (K,)."""
    if t <= times[0] or len(times) == 1:
        return mats[0].copy()
    if t >= times[-1]:
        return mats[-1].copy()
    j = int(np.searchsorted(times, t, side="right"))
    i = j - 1
    u = (t - times[i]) / (times[j] - times[i])
    if u == 0.0:
        return mats[i].copy()
    (ti, qi, si), (tj, qj, sj) = split(mats[i]), split(mats[j])
    out = np.eye(4)
    out[:3, :3] = ((1 - u) * si + u * sj) * rotation_matrix(slerp(qi, qj, u))
    out[:3, 3] = (1 - u) * ti + u * tj
    return out
