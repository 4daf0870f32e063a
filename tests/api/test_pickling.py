"""Everything a user may send to a worker process pickles, deep-copies and round-trips to
identical renders: Mesh, Scene (with its objects, motions, lights, camera), BlurShell (with its
whole history) and ContourTable; checked with pickle, copy.deepcopy and a real process pool."""

from __future__ import annotations

import copy
import hashlib
import multiprocessing
import pickle

import numpy as np
import pytest

import motionblur as mb


def _digest(frame) -> str:
    h = hashlib.sha256()
    for a in (frame.rgba, frame.depth, frame.ids, frame.velocity):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def _render(scene) -> str:
    return _digest(mb.render(scene, "accumulation", samples=4))


def _render_volume(scene) -> str:
    return _digest(mb.render(scene, "motion_volume", segments=2))


def _shell_build(shell_and_pos):
    shell, pos = shell_and_pos
    shell.update(pos[-2])
    out = shell.build(pos[-1])
    return out.vertices.tobytes() + out.rgba.tobytes() + out.faces.tobytes()


def _table_edges(table):
    return [table.edges(i).tobytes() for i in range(len(table))]


COPIES = {
    "pickle": lambda x: pickle.loads(pickle.dumps(x)),
    "pickle protocol 2": lambda x: pickle.loads(pickle.dumps(x, protocol=2)),
    "deepcopy": copy.deepcopy,
}


@pytest.mark.parametrize("how", sorted(COPIES))
def test_a_mesh_round_trips(how):
    v, f = mb.meshes.icosphere(2)
    mesh = mb.Mesh(v, f)
    mesh.edges()  # the adjacency is built: the copy builds its own
    other = COPIES[how](mesh)
    assert other is not mesh and isinstance(other, mb.Mesh)
    np.testing.assert_array_equal(other.vertices, mesh.vertices)
    np.testing.assert_array_equal(other.faces, mesh.faces)
    assert not other.vertices.flags.writeable and not other.faces.flags.writeable
    assert other.stats == mesh.stats
    np.testing.assert_array_equal(other.edges(), mesh.edges())
    np.testing.assert_array_equal(mb.contour_edges(other, [1, 0.2, 0]), mb.contour_edges(mesh, [1, 0.2, 0]))


@pytest.mark.parametrize("how", sorted(COPIES))
@pytest.mark.parametrize("name", ["cube", "bending_arm", "pan"])
def test_a_scene_round_trips_to_identical_renders(how, name):
    scene = mb.SCENES[name](40, 30)
    other = COPIES[how](scene)
    assert other is not scene and len(other.objects) == len(scene.objects)
    assert _render(other) == _render(scene)
    if name == "cube":
        assert _render_volume(other) == _render_volume(scene)


@pytest.mark.parametrize("how", sorted(COPIES))
def test_a_blur_shell_round_trips_with_its_history(how):
    pos, faces = mb.meshes.bending_arm(12)
    shell = mb.BlurShell(faces, subdivisions=5, hysteresis=2, initial_alpha=0.8, color=(0.2, 0.5, 1.0))
    fresh = COPIES[how](shell)  # before any update
    assert fresh.updates == 0 and fresh.build().is_empty
    for p in pos[:7]:
        shell.update(p)
    other = COPIES[how](shell)
    assert other.updates == shell.updates == 7
    for k, v in shell.state().items():
        np.testing.assert_array_equal(other.state()[k], v, err_msg=k)
    # both go on alike: the same updates give the same shells, bit for bit
    for p in pos[7:]:
        shell.update(p)
        other.update(p)
        a, b = shell.build(), other.build()
        for name in ("vertices", "faces", "rgba", "normals", "face", "step"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert not shell.build().is_empty


def test_a_shell_refuses_the_history_of_another_shell():
    pos, faces = mb.meshes.bending_arm(4)
    a = mb.BlurShell(faces, subdivisions=3)
    a.update(pos[0])
    state = a.__getstate__()
    state["subdivisions"] = 4
    b = mb.BlurShell.__new__(mb.BlurShell)
    with pytest.raises(ValueError, match="state: is the history of a shell of .* 3 subdivisions"):
        b.__setstate__(state)
    state["subdivisions"] = 3
    state["history"] = state["history"][:-1]
    with pytest.raises(ValueError, match="state: is truncated|state: has"):
        b.__setstate__(state)


@pytest.mark.parametrize("how", sorted(COPIES))
def test_a_contour_table_round_trips(how):
    mesh = mb.Mesh(*mb.meshes.icosphere(2))
    for table in (mb.ContourTable(mesh, 16, seed=3), mb.ContourTable(mesh, np.eye(3) + 0.1)):
        other = COPIES[how](table)
        np.testing.assert_array_equal(other.directions, table.directions)
        assert _table_edges(other) == _table_edges(table)
        assert other.lookup([1, 0.5, 0])[1] == table.lookup([1, 0.5, 0])[1]


def test_objects_sent_to_a_process_pool_come_back_with_identical_results():
    scene = mb.SCENES["cube"](40, 30)
    pos, faces = mb.meshes.bending_arm(8)
    shell = mb.BlurShell(faces, subdivisions=4)
    for p in pos[:5]:
        shell.update(p)
    table = mb.ContourTable(mb.Mesh(*mb.meshes.icosphere(2)), 8)
    ctx = multiprocessing.get_context("spawn")  # a fresh interpreter: nothing shared but the pickles
    with ctx.Pool(1) as pool:
        remote_scene = pool.apply(_render, (scene,))
        remote_volume = pool.apply(_render_volume, (scene,))
        remote_shell = pool.apply(_shell_build, ((shell, pos),))
        remote_table = pool.apply(_table_edges, (table,))
    assert remote_scene == _render(scene)
    assert remote_volume == _render_volume(scene)
    assert remote_table == _table_edges(table)
    assert remote_shell == _shell_build((copy.deepcopy(shell), pos))
