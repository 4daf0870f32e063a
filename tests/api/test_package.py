"""The package imports, exposes its version, and its argument checks name the argument."""

import numpy as np
import pytest

import motionblur
from motionblur import _validate, meshes


def test_version_matches_core():
    assert motionblur.__version__ == motionblur._core.__version__
    assert motionblur.__version__.count(".") == 2


def test_public_names_exist():
    for name in motionblur.__all__:
        assert hasattr(motionblur, name), name


@pytest.mark.parametrize(
    "value, exc, text",
    [
        (np.zeros((3, 2)), ValueError, "vertices: expected shape (N,3)"),
        (np.array([[np.nan, 0, 0]]), ValueError, "vertices: contains NaN"),
        (np.zeros((0, 3)), ValueError, "vertices: is empty"),
        (np.array([["a", "b", "c"]]), TypeError, "vertices: expected a numeric array"),
    ],
)
def test_as_array_names_the_argument(value, exc, text):
    with pytest.raises(exc) as err:
        _validate.as_array(value, "vertices", np.float64, (None, 3))
    assert text in str(err.value)


def test_as_array_never_writes_the_callers_array():
    src = np.arange(12, dtype=np.float32).reshape(4, 3)
    before = src.copy()
    out = _validate.as_array(src, "vertices", np.float64, (None, 3))
    out += 1
    np.testing.assert_array_equal(src, before)


def test_integer_faces_reject_floats():
    with pytest.raises(TypeError, match="faces: expected an integer array"):
        _validate.as_array(np.zeros((2, 3)), "faces", np.int64, (None, 3))


@pytest.mark.parametrize("sub", [0, 1, 3])
def test_icosphere_is_closed_and_outward(sub):
    v, f = meshes.icosphere(sub)
    assert len(f) == 20 * 4**sub
    # Closed: every undirected edge is used by exactly two faces, once in each direction.
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    assert len(np.unique(e, axis=0)) == len(e)
    # Outward: the signed volume is positive and close to the sphere's.
    vol = np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum() / 6.0
    assert 0.6 * 4 / 3 * np.pi < vol <= 4 / 3 * np.pi


@pytest.mark.parametrize(
    "make", [meshes.box, meshes.torus, meshes.cylinder, meshes.uv_sphere], ids=lambda m: m.__name__
)
def test_builtin_meshes_are_closed_and_outward(make):
    v, f = make()
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    assert len(np.unique(e, axis=0)) == len(e), "an edge is used twice in the same direction"
    rev = {tuple(x) for x in e[:, ::-1]}
    assert all(tuple(x) in rev for x in e), "open edge"
    vol = np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum() / 6.0
    assert vol > 0
