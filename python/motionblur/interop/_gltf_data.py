"""The data of a loaded glTF 2.0 file as numpy: accessors, primitives, node placements at any
animation time, morph targets and skins ([`gltf`][motionblur.interop.gltf] turns them into scene parts).

glTF conventions used here: matrices are stored column-major; rotations are unit quaternions
``(x, y, z, w)``; a node's local placement is ``T @ R @ S`` (or its ``matrix``); times are
seconds; colours are linear.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["GltfData", "quat_to_matrix", "sample_channel"]

_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_NORM = {np.int8: 127.0, np.uint8: 255.0, np.int16: 32767.0, np.uint16: 65535.0, np.uint32: 4294967295.0}
_TRIANGLES, _STRIP, _FAN = 4, 5, 6


def quat_to_matrix(q) -> np.ndarray:
    """(3,3) rotation of the glTF quaternion ``q`` = (x, y, z, w), normalised first."""
    x, y, z, w = np.asarray(q, np.float64) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _slerp(q0: np.ndarray, q1: np.ndarray, u: float) -> np.ndarray:
    q0, q1 = q0 / np.linalg.norm(q0), q1 / np.linalg.norm(q1)
    d = float(q0 @ q1)
    if d < 0.0:
        q1, d = -q1, -d
    if d > 0.9995:
        q = q0 + u * (q1 - q0)
        return q / np.linalg.norm(q)
    theta = np.arccos(min(1.0, d))
    return (np.sin((1 - u) * theta) * q0 + np.sin(u * theta) * q1) / np.sin(theta)


def sample_channel(
    keys: np.ndarray, values: np.ndarray, interpolation: str, path: str, s: float
) -> np.ndarray:
    """The value of one animation sampler at time ``s`` seconds: ``keys`` (K,), ``values`` (K,n)
    (``CUBICSPLINE``: (3K,n), in-tangent, value, out-tangent per key); held before the first and
    after the last key; rotations slerped (``LINEAR``) or normalised (``CUBICSPLINE``)."""
    cubic = interpolation == "CUBICSPLINE"
    vals = values[1::3] if cubic else values
    if s <= keys[0] or len(keys) == 1:
        return vals[0].copy()
    if s >= keys[-1]:
        return vals[-1].copy()
    j = int(np.searchsorted(keys, s, side="right"))
    i = j - 1
    if interpolation == "STEP":
        return vals[i].copy()
    dt = keys[j] - keys[i]
    u = (s - keys[i]) / dt
    if cubic:
        p0, m0 = values[3 * i + 1], dt * values[3 * i + 2]
        p1, m1 = values[3 * j + 1], dt * values[3 * j]
        u2, u3 = u * u, u * u * u
        out = (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * m0 + (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * m1
        return out / np.linalg.norm(out) if path == "rotation" else out
    if path == "rotation":
        return _slerp(vals[i], vals[j], u)
    return (1 - u) * vals[i] + u * vals[j]


class GltfData:
    """A pygltflib ``GLTF2`` of the file at ``path`` with its buffers read once; ``anim`` (set by
    the reader) is the animation that moves it, or None."""

    def __init__(self, gltf, path: Path):
        self.gltf = gltf
        self.path = path
        self.anim = None
        self._anim_cache: dict[int, dict[int, dict[str, tuple]]] = {}
        self._buffers: dict[int, bytes] = {}
        self._cache: dict[int, np.ndarray] = {}
        self.parent = {c: i for i, n in enumerate(gltf.nodes) for c in (n.children or [])}

    # ---------------------------------------------------------------- accessors

    def _buffer(self, index: int) -> bytes:
        if index not in self._buffers:
            buf = self.gltf.buffers[index]
            data = self.gltf.get_data_from_buffer_uri(buf.uri)
            if data is None:
                raise ValueError(
                    f"path: buffer {index} of {str(self.path)!r} cannot be read (uri {buf.uri!r})"
                )
            self._buffers[index] = bytes(data)
        return self._buffers[index]

    def _view(self, view: int, offset: int, dtype, count: int, width: int) -> np.ndarray:
        bv = self.gltf.bufferViews[view]
        item = np.dtype(dtype).itemsize
        stride = bv.byteStride or item * width
        start = (bv.byteOffset or 0) + (offset or 0)
        buf = self._buffer(bv.buffer)
        if count and start + stride * (count - 1) + item * width > len(buf):
            raise ValueError(f"path: accessor data of buffer view {view} runs past its buffer")
        return np.ndarray((count, width), dtype, buf, start, (stride, item)).copy()

    def accessor(self, index: int) -> np.ndarray:
        """(count, n) array of accessor ``index``: float64 for float or normalized data, else
        the stored integer type; sparse values applied."""
        if index in self._cache:
            return self._cache[index]
        a = self.gltf.accessors[index]
        dtype, width = _DTYPES[a.componentType], _WIDTH[a.type]
        if a.bufferView is None:
            out = np.zeros((a.count, width), dtype)
        else:
            out = self._view(a.bufferView, a.byteOffset, dtype, a.count, width)
        if a.sparse is not None and a.sparse.count:
            sp = a.sparse
            idx = self._view(sp.indices.bufferView, sp.indices.byteOffset, _DTYPES[sp.indices.componentType],
                             sp.count, 1)[:, 0]  # fmt: skip
            out[idx] = self._view(sp.values.bufferView, sp.values.byteOffset, dtype, sp.count, width)
        if dtype == np.float32:
            out = out.astype(np.float64)
        elif a.normalized:
            out = np.maximum(out.astype(np.float64) / _NORM[dtype], -1.0)
        self._cache[index] = out
        return out

    # ---------------------------------------------------------------- nodes

    def scene_nodes(self) -> list[int]:
        """Every node of the file's scene (its default one, else the first, else all roots),
        parents before children."""
        g = self.gltf
        if g.scenes:
            roots = list(g.scenes[g.scene if g.scene is not None else 0].nodes or [])
        else:
            roots = [i for i in range(len(g.nodes)) if i not in self.parent]
        out, stack = [], roots[::-1]
        while stack:
            i = stack.pop()
            out.append(i)
            stack.extend((g.nodes[i].children or [])[::-1])
        return out

    def _local(self, i: int, s: float) -> np.ndarray:
        n = self.gltf.nodes[i]
        animated = {} if self.anim is None else self._channels(self.anim).get(i, {})
        if n.matrix is not None and not animated:
            return np.asarray(n.matrix, np.float64).reshape(4, 4).T
        t = np.asarray(n.translation if n.translation is not None else [0, 0, 0], np.float64)
        r = np.asarray(n.rotation if n.rotation is not None else [0, 0, 0, 1], np.float64)
        sc = np.asarray(n.scale if n.scale is not None else [1, 1, 1], np.float64)
        if "translation" in animated:
            t = sample_channel(*animated["translation"], "translation", s)
        if "rotation" in animated:
            r = sample_channel(*animated["rotation"], "rotation", s)
        if "scale" in animated:
            sc = sample_channel(*animated["scale"], "scale", s)
        m = np.eye(4)
        m[:3, :3] = quat_to_matrix(r) * sc
        m[:3, 3] = t
        return m

    def _channels(self, anim) -> dict[int, dict[str, tuple]]:
        """{node: {path: (keys, values, interpolation)}} of ``anim`` (cached on it)."""
        key = id(anim)
        if key not in self._anim_cache:
            out: dict[int, dict[str, tuple]] = {}
            for ch in anim.channels:
                if ch.target is None or ch.target.node is None:
                    continue
                smp = anim.samplers[ch.sampler]
                keys = self.accessor(smp.input)[:, 0].astype(np.float64)
                vals = self.accessor(smp.output).astype(np.float64)
                if ch.target.path == "weights":
                    per_key = 3 * len(keys) if smp.interpolation == "CUBICSPLINE" else len(keys)
                    vals = vals.reshape(per_key, -1)
                out.setdefault(ch.target.node, {})[ch.target.path] = (
                    keys,
                    vals,
                    smp.interpolation or "LINEAR",
                )
            self._anim_cache[key] = out
        return self._anim_cache[key]

    def world_poses(self, s: float) -> np.ndarray:
        """(nodes, 4, 4) world placement of every node at animation time ``s`` seconds."""
        n = len(self.gltf.nodes)
        world = np.tile(np.eye(4), (n, 1, 1))
        for i in self.scene_nodes():
            local = self._local(i, s)
            p = self.parent.get(i)
            world[i] = local if p is None else world[p] @ local
        return world

    # ---------------------------------------------------------------- primitives

    def _prim(self, node: int, p: int):
        return self.gltf.meshes[self.gltf.nodes[node].mesh].primitives[p]

    def triangles(self, node: int, p: int) -> np.ndarray | None:
        """(F,3) int64 triangles of a primitive (strips and fans unrolled, counter-clockwise),
        or None for points and lines."""
        prim = self._prim(node, p)
        mode = _TRIANGLES if prim.mode is None else prim.mode
        if mode not in (_TRIANGLES, _STRIP, _FAN) or prim.attributes.POSITION is None:
            return None
        count = self.gltf.accessors[prim.attributes.POSITION].count
        idx = (
            np.arange(count, dtype=np.int64)
            if prim.indices is None
            else self.accessor(prim.indices)[:, 0].astype(np.int64)
        )
        if mode == _TRIANGLES:
            f = idx[: len(idx) // 3 * 3].reshape(-1, 3)
        elif mode == _STRIP:
            k = np.arange(len(idx) - 2)
            even = k % 2 == 0
            f = np.stack(
                [idx[k], np.where(even, idx[k + 1], idx[k + 2]), np.where(even, idx[k + 2], idx[k + 1])],
                axis=1,
            )
        else:
            k = np.arange(1, len(idx) - 1)
            f = np.stack([np.full(len(k), idx[0]), idx[k], idx[k + 1]], axis=1)
        return f if len(f) else None

    def primitive(self, node: int, p: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(local positions (V,3) float64, faces (F,3) int64, colour (4,) or (V,4) float32)."""
        prim = self._prim(node, p)
        v = self.accessor(prim.attributes.POSITION).astype(np.float64)
        faces = self.triangles(node, p)
        factor = np.ones(4)
        mode, cutoff = "OPAQUE", 0.5
        if prim.material is not None:
            mat = self.gltf.materials[prim.material]
            pbr = mat.pbrMetallicRoughness
            if pbr is not None and pbr.baseColorFactor is not None:
                factor = np.asarray(pbr.baseColorFactor, np.float64)
            mode = mat.alphaMode or "OPAQUE"
            cutoff = 0.5 if mat.alphaCutoff is None else float(mat.alphaCutoff)
        colour = factor
        if getattr(prim.attributes, "COLOR_0", None) is not None:
            c = self.accessor(prim.attributes.COLOR_0).astype(np.float64)
            c = np.concatenate([c, np.ones((len(c), 1))], axis=1) if c.shape[1] == 3 else c
            colour = c * factor
        colour = np.array(colour, np.float64)
        if mode == "OPAQUE":
            colour[..., 3] = 1.0
        elif mode == "MASK":
            colour[..., 3] = (colour[..., 3] >= cutoff).astype(np.float64)
        if colour.ndim == 2 and (colour == colour[0]).all():
            colour = colour[0]
        return v, faces, np.clip(colour, 0.0, None).astype(np.float32)

    def morph_positions(self, node: int, p: int, secs: np.ndarray) -> np.ndarray | None:
        """(K,V,3) local positions with the morph targets weighted at each time of ``secs``, or
        None for a primitive without ``POSITION`` targets."""
        prim = self._prim(node, p)
        targets = [
            t.get("POSITION") if isinstance(t, dict) else getattr(t, "POSITION", None)
            for t in (prim.targets or [])
        ]
        if not targets or all(t is None for t in targets):
            return None
        base = self.accessor(prim.attributes.POSITION).astype(np.float64)
        d = np.stack([np.zeros_like(base) if t is None else self.accessor(t) for t in targets])
        n = self.gltf.nodes[node]
        w0 = np.asarray(
            getattr(n, "weights", None) or self.gltf.meshes[n.mesh].weights or [0.0] * len(targets),
            np.float64,
        )
        animated = None if self.anim is None else self._channels(self.anim).get(node, {}).get("weights")
        out = []
        for s in secs:
            w = w0 if animated is None else sample_channel(*animated, "weights", s)
            out.append(base + np.tensordot(w[: len(d)], d, axes=1))
        return np.stack(out)

    def has_skin_attributes(self, node: int, p: int) -> bool:
        a = self._prim(node, p).attributes
        return getattr(a, "JOINTS_0", None) is not None and getattr(a, "WEIGHTS_0", None) is not None

    def skin(self, node: int, p: int, local: np.ndarray, world: np.ndarray) -> np.ndarray:
        """(V,3) world positions of the skinned ``local`` positions (V,3) under the node
        placements ``world`` (nodes,4,4): sum over the vertex's joints of weight x joint world x
        inverse bind matrix."""
        skin = self.gltf.skins[self.gltf.nodes[node].skin]
        joints = list(skin.joints)
        if skin.inverseBindMatrices is not None:
            ibm = self.accessor(skin.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1)
        else:
            ibm = np.tile(np.eye(4), (len(joints), 1, 1))
        mats = np.stack([world[j] for j in joints]) @ ibm  # (J,4,4)
        a = self._prim(node, p).attributes
        j_idx = self.accessor(a.JOINTS_0).astype(np.int64)
        w = self.accessor(a.WEIGHTS_0).astype(np.float64)
        total = w.sum(axis=1, keepdims=True)
        w = w / np.where(total > 0, total, 1.0)
        homog = np.concatenate([local, np.ones((len(local), 1))], axis=1)
        per = np.einsum("vkij,vj->vki", mats[j_idx], homog)  # (V,4 joints,4)
        return np.einsum("vk,vki->vi", w, per)[:, :3]
