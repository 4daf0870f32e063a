"""A plain numpy twin of BlurShell.update/build, written from the rules in motionblur.shell's
docstring (float32 facing, rings of edge codes, birth element, hysteresis then fade, alpha
``a * (1 - max(j, d) / S)``). The Rust shell must match it exactly."""

from __future__ import annotations

import numpy as np

NO_EDGE = 3
ON = 4


def twin_normals(p32: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unnormalised float32 vertex normals: raw face normals added in face order (np.add.at)."""
    a, b, c = p32[faces[:, 0]], p32[faces[:, 1]], p32[faces[:, 2]]
    fn = np.cross(b - a, c - a)
    vn = np.zeros((len(p32), 3), np.float32)
    np.add.at(vn, faces.ravel(), np.repeat(fn, 3, axis=0))
    return vn


def twin_facing(n32: np.ndarray, p32: np.ndarray, prev32: np.ndarray) -> np.ndarray:
    """0 for a vertex that does not move, else -1 when n . d < 0 and +1 otherwise (n . d >= 0)."""
    d = p32 - prev32
    s = n32[:, 0] * d[:, 0] + n32[:, 1] * d[:, 1] + n32[:, 2] * d[:, 2]
    moves = (d != 0).any(axis=1)
    return np.where(moves, np.where(s < 0, -1, 1), 0).astype(np.int8)


def twin_face_edge(facing: np.ndarray, faces: np.ndarray) -> np.ndarray:
    s = facing[faces].astype(np.int64)
    ok = (s.sum(axis=1) == -1) & (s != 0).all(axis=1)
    j = np.argmax(s == 1, axis=1)
    return np.where(ok, (j + 1) % 3, NO_EDGE).astype(np.int64)


def _unit32(n: np.ndarray) -> np.ndarray:
    n = n.astype(np.float64)
    length = np.sqrt(n[:, 0] * n[:, 0] + n[:, 1] * n[:, 1] + n[:, 2] * n[:, 2])
    ok = (length > 0) & np.isfinite(length)
    out = np.zeros_like(n)
    out[ok] = n[ok] / length[ok, None]
    return out.astype(np.float32)


class TwinShell:
    def __init__(
        self, faces, n_vertices, subdivisions=10, hysteresis=3, initial_alpha=1.0, mask=None, color=None
    ):
        self.faces = np.asarray(faces, np.int64)
        self.nv, self.S, self.h = n_vertices, subdivisions, hysteresis
        self.a = np.float32(initial_alpha)
        f = len(self.faces)
        self.mask = np.ones(f, bool) if mask is None else np.asarray(mask, bool)
        c = np.ones((1, 3), np.float32) if color is None else np.asarray(color, np.float32).reshape(-1, 3)
        self.color = c
        self.ring = np.full((self.S, f), NO_EDGE, np.int64)
        self.last = np.full(f, NO_EDGE, np.int64)
        self.fade = np.full(f, 255, np.int64)
        self.run = np.zeros(f, np.int64)
        self.since = np.full(f, 65535, np.int64)
        self.pos = [None] * self.S
        self.nrm = [None] * self.S
        self.n = 0
        self.facing = np.zeros(n_vertices, np.int8)

    def update(self, vertices, normals=None):
        p32 = np.asarray(vertices, np.float64).astype(np.float32)
        n32 = (
            twin_normals(p32, self.faces)
            if normals is None
            else np.asarray(normals, np.float64).astype(np.float32)
        )
        S, slot = self.S, self.n % self.S
        if self.n > 0:
            self.facing = twin_facing(n32, p32, self.pos[(self.n - 1) % S])
        else:
            self.facing = np.zeros(self.nv, np.int8)
        self.pos[slot], self.nrm[slot] = p32, n32
        code = np.where(self.mask, twin_face_edge(self.facing, self.faces), NO_EDGE)
        alive = self.fade < S
        on = code != NO_EDGE
        born, cont = on & ~alive, on & alive
        self.fade[cont] = np.maximum(self.fade[cont] - 1, 0)
        self.run[cont] = np.minimum(self.run[cont] + 1, S)
        self.fade[born] = 0
        self.run[born] = min(2, S)
        self.ring[(slot - 1) % S, born] = code[born]
        self.last[on] = code[on]
        self.since[on] = 0
        self.ring[slot, on] = code[on] | ON
        off = ~on
        self.since[off] = np.minimum(self.since[off] + 1, 65535)
        fading = off & alive
        self.fade[fading & (self.since > self.h)] += 1
        still = fading & (self.fade < S)
        self.run[still] = np.minimum(self.run[still] + 1, S)
        self.ring[slot, still] = self.last[still]
        self.run[fading & ~still] = 0
        self.n += 1

    def build(self, vertices=None, normals=None):
        S = self.S
        if self.n == 0:
            return None
        newest = (self.n - 1) % S
        V, T, C, N, FA, ST = [], [], [], [], [], []
        base_n = None if normals is None else _unit32(np.asarray(normals, np.float64))
        for f in range(len(self.faces)):
            if not (self.fade[f] < S and self.run[f] > 0):
                continue
            start = len(V)
            pairs = self.run[f] + 1
            for j in range(pairs):
                if j == 0:
                    k, slot = self.last[f], newest
                else:
                    slot = (newest - (j - 1)) % S
                    k = self.ring[slot, f] & 3
                alpha = self.a * (np.float32(1.0) - np.float32(max(j, self.fade[f])) / np.float32(S))
                for corner in (k, (k + 1) % 3):
                    vtx = self.faces[f, corner]
                    if j == 0 and vertices is not None:
                        V.append(np.asarray(vertices, np.float64)[vtx])
                    else:
                        V.append(self.pos[slot][vtx].astype(np.float64))
                    if j == 0 and base_n is not None:
                        N.append(base_n[vtx])
                    else:
                        N.append(_unit32(self.nrm[slot][vtx][None])[0])
                    rgb = self.color[0] if len(self.color) == 1 else self.color[vtx]
                    C.append(np.array([*rgb, alpha], np.float32))
                    FA.append(f)
                    ST.append(j)
            for j in range(pairs - 1):
                b = start + 2 * j
                T += [[b, b + 1, b + 3], [b, b + 3, b + 2]]
        return {
            "vertices": np.array(V, np.float64).reshape(-1, 3),
            "faces": np.array(T, np.int64).reshape(-1, 3),
            "rgba": np.array(C, np.float32).reshape(-1, 4),
            "normals": np.array(N, np.float32).reshape(-1, 3),
            "face": np.array(FA, np.int64),
            "step": np.array(ST, np.int32),
        }
