"""Small animated glTF 2.0 files written with pygltflib, for the glTF reader's tests.

:func:`animated_asset` builds one file's worth of nodes, meshes and one animation, and
:func:`write` saves it in the three layouts of the Khronos sample models: ``glTF`` (JSON and a
``.bin`` beside it), ``glTF-Embedded`` (the buffer as a data URI) and ``glTF-Binary`` (``.glb``).
The test knows every value it wrote (``ASSET``) and checks the reader against them.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pygltflib as g

# A unit cube (8 vertices, 12 triangles, counter-clockwise outward).
CUBE_V = np.array(
    [[-0.5, -0.5, -0.5], [0.5, -0.5, -0.5], [0.5, 0.5, -0.5], [-0.5, 0.5, -0.5],
     [-0.5, -0.5, 0.5], [0.5, -0.5, 0.5], [0.5, 0.5, 0.5], [-0.5, 0.5, 0.5]], np.float32)  # fmt: skip
CUBE_F = np.array(
    [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
     [2, 3, 7], [2, 7, 6], [1, 2, 6], [1, 6, 5], [0, 4, 7], [0, 7, 3]], np.uint16)  # fmt: skip


def quat_z(angle: float) -> list[float]:
    """glTF quaternion (x, y, z, w) of a rotation by ``angle`` radians about +Z."""
    return [0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2)]


#: What the asset holds; the tests compare the reader with these values.
ASSET = {
    "parent_translation": [0.0, 0.5, 0.0],
    "cube_color": [0.9, 0.1, 0.05, 1.0],
    "cube_keys": [0.0, 1.0, 2.0],  # seconds
    "cube_translation": [[-1.0, 0.0, 0.0], [0.0, 0.3, 0.0], [1.0, 0.0, 0.0]],
    "cube_rotation": [quat_z(0.0), quat_z(0.4), quat_z(0.8)],
    "step_keys": [0.0, 1.5],
    "step_scale": [[1.0, 1.0, 1.0], [1.25, 1.25, 1.25]],
    "morph_keys": [0.0, 2.0],
    "morph_weights": [0.0, 1.0],
    "morph_offset": [0.0, 0.0, 0.6],  # the target's displacement of vertex 6 (a top corner)
    "joint_keys": [0.0, 2.0],
    "joint_rotation": [quat_z(0.0), quat_z(0.6)],
    "camera_translation": [0.0, 0.0, 7.0],
    "camera_yfov": 0.7,
}


class _Builder:
    def __init__(self) -> None:
        self.blob = bytearray()
        self.gltf = g.GLTF2(asset=g.Asset(version="2.0"), scene=0)

    def accessor(self, array: np.ndarray, kind: str, target=None, minmax: bool = False) -> int:
        array = np.ascontiguousarray(array)
        while len(self.blob) % 4:
            self.blob.append(0)
        view = g.BufferView(buffer=0, byteOffset=len(self.blob), byteLength=array.nbytes, target=target)
        self.blob += array.tobytes()
        self.gltf.bufferViews.append(view)
        comp = {
            np.dtype(np.float32): g.FLOAT,
            np.dtype(np.uint16): g.UNSIGNED_SHORT,
            np.dtype(np.uint8): g.UNSIGNED_BYTE,
        }
        count = len(array) if kind != "SCALAR" or array.ndim == 1 else array.size
        acc = g.Accessor(
            bufferView=len(self.gltf.bufferViews) - 1, componentType=comp[array.dtype], count=count, type=kind
        )
        if minmax:
            flat = array.reshape(count, -1)
            acc.min, acc.max = flat.min(axis=0).tolist(), flat.max(axis=0).tolist()
        self.gltf.accessors.append(acc)
        return len(self.gltf.accessors) - 1

    def mesh(self, material: int, *, targets=None, skin_attrs=None, offset=(0.0, 0.0, 0.0)) -> int:
        pos = self.accessor(CUBE_V + np.float32(offset), "VEC3", g.ARRAY_BUFFER, minmax=True)
        idx = self.accessor(CUBE_F.ravel(), "SCALAR", g.ELEMENT_ARRAY_BUFFER)
        attrs = g.Attributes(POSITION=pos)
        if skin_attrs is not None:
            attrs.JOINTS_0 = self.accessor(skin_attrs[0], "VEC4", g.ARRAY_BUFFER)
            attrs.WEIGHTS_0 = self.accessor(skin_attrs[1], "VEC4", g.ARRAY_BUFFER)
        prim = g.Primitive(attributes=attrs, indices=idx, material=material)
        if targets is not None:
            prim.targets = [
                {"POSITION": self.accessor(t, "VEC3", g.ARRAY_BUFFER, minmax=True)} for t in targets
            ]
        self.gltf.meshes.append(
            g.Mesh(primitives=[prim], weights=[0.0] * len(targets) if targets is not None else None)
        )
        return len(self.gltf.meshes) - 1

    def channel(self, anim: g.Animation, node: int, path: str, keys, values, interpolation="LINEAR") -> None:
        kind = {"translation": "VEC3", "scale": "VEC3", "rotation": "VEC4", "weights": "SCALAR"}[path]
        i = self.accessor(np.asarray(keys, np.float32), "SCALAR", minmax=True)
        o = self.accessor(np.asarray(values, np.float32), kind)
        anim.samplers.append(g.AnimationSampler(input=i, output=o, interpolation=interpolation))
        anim.channels.append(
            g.AnimationChannel(
                sampler=len(anim.samplers) - 1, target=g.AnimationChannelTarget(node=node, path=path)
            )
        )


def animated_asset(parts=("cube", "morph", "skin", "camera"), animated: bool = True) -> tuple[g.GLTF2, bytes]:
    """(gltf, its binary buffer): a static parent node (translated) holding an animated red cube
    (LINEAR translation and rotation, STEP scale), a cube with a morph target whose weight is
    animated, a cube skinned to two joints of which one turns, and a camera, as ``parts`` says.
    ``animated=False`` leaves the animation out (the rest pose)."""
    a, b = ASSET, _Builder()
    gl = b.gltf
    gl.materials = [g.Material(pbrMetallicRoughness=g.PbrMetallicRoughness(baseColorFactor=a["cube_color"]))]
    gl.materials.append(
        g.Material(pbrMetallicRoughness=g.PbrMetallicRoughness(baseColorFactor=[0.1, 0.4, 0.9, 1.0]))
    )
    anim = g.Animation(name="move")
    gl.nodes.append(g.Node(name="parent", translation=a["parent_translation"], children=[]))
    roots = [0]
    if "cube" in parts:
        gl.nodes.append(g.Node(name="cube", mesh=b.mesh(0)))
        cube = len(gl.nodes) - 1
        gl.nodes[0].children.append(cube)
        b.channel(anim, cube, "translation", a["cube_keys"], a["cube_translation"])
        b.channel(anim, cube, "rotation", a["cube_keys"], a["cube_rotation"])
        b.channel(anim, cube, "scale", a["step_keys"], a["step_scale"], "STEP")
    if "morph" in parts:
        target = np.zeros_like(CUBE_V)
        target[6] = a["morph_offset"]
        gl.nodes.append(g.Node(name="morph", mesh=b.mesh(1, targets=[target]), translation=[0.0, -1.5, 0.0]))
        morph = len(gl.nodes) - 1
        roots.append(morph)
        b.channel(anim, morph, "weights", a["morph_keys"], a["morph_weights"])
    if "skin" in parts:
        joints = np.zeros((8, 4), np.uint8)
        joints[:, 0] = (CUBE_V[:, 0] > 0).astype(np.uint8)  # the +x half follows joint 1
        weights = np.zeros((8, 4), np.float32)
        weights[:, 0] = 1.0
        gl.nodes.append(g.Node(name="joint0", translation=[0.0, 1.5, 0.0], children=[]))
        j0 = len(gl.nodes) - 1
        gl.nodes.append(g.Node(name="joint1", translation=[0.0, 0.0, 0.0]))
        j1 = len(gl.nodes) - 1
        gl.nodes[j0].children.append(j1)
        ibm = (
            np.stack([np.linalg.inv(_translation([0.0, 1.5, 0.0]))] * 2).transpose(0, 2, 1).astype(np.float32)
        )
        gl.skins.append(g.Skin(joints=[j0, j1], inverseBindMatrices=b.accessor(ibm.reshape(2, 16), "MAT4")))
        gl.nodes.append(
            g.Node(
                name="skinned",
                mesh=b.mesh(1, skin_attrs=(joints, weights), offset=(0.0, 1.5, 0.0)),
                skin=0,
                translation=[0.0, 1.5, 0.0],
            )
        )
        roots += [j0, len(gl.nodes) - 1]
        b.channel(anim, j1, "rotation", a["joint_keys"], a["joint_rotation"])
    if "camera" in parts:
        gl.cameras.append(
            g.Camera(
                type="perspective", perspective=g.Perspective(yfov=a["camera_yfov"], znear=0.1, zfar=100.0)
            )
        )
        gl.nodes.append(g.Node(name="camera", camera=0, translation=a["camera_translation"]))
        roots.append(len(gl.nodes) - 1)
    gl.scenes = [g.Scene(nodes=roots)]
    if animated:
        gl.animations = [anim]
    gl.buffers = [g.Buffer(byteLength=len(b.blob))]
    return gl, bytes(b.blob)


def _translation(t) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = t
    return m


def write(folder: Path, layout: str, gl: g.GLTF2, blob: bytes, name: str = "asset") -> Path:
    """Save ``gl`` with ``blob`` under ``folder`` in ``layout``: ``"glTF"``, ``"glTF-Embedded"``
    or ``"glTF-Binary"``; returns the file to load."""
    folder = Path(folder) / layout
    folder.mkdir(parents=True, exist_ok=True)
    gl.set_binary_blob(blob)
    gl.buffers[0].uri = None
    if layout == "glTF-Binary":
        path = folder / f"{name}.glb"
        gl.save_binary(str(path))
    elif layout == "glTF-Embedded":
        gl.convert_buffers(g.BufferFormat.DATAURI)
        path = folder / f"{name}.gltf"
        gl.save_json(str(path))
    else:
        (folder / f"{name}.bin").write_bytes(blob)
        gl.buffers[0].uri = f"{name}.bin"
        gl.destroy_binary_blob()
        path = folder / f"{name}.gltf"
        gl.save_json(str(path))
    return path
