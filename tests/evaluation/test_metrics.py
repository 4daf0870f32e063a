"""The image metrics against their numpy definitions."""

from __future__ import annotations

import numpy as np
import pytest

from motionblur.evaluation import metrics


def test_metrics_against_numpy(rng):
    a = rng.random((16, 20, 4)).astype(np.float32)
    b = np.clip(a + rng.normal(0, 0.05, a.shape), 0, 1).astype(np.float32)
    assert metrics.rmse(a, b) == pytest.approx(np.sqrt(np.mean((a.astype(float) - b) ** 2)))
    assert metrics.psnr(a, b) == pytest.approx(-20 * np.log10(metrics.rmse(a, b)))
    assert metrics.psnr(a, a) == np.inf and metrics.flip(a, a) == 0.0
    assert 0.0 < metrics.flip(a, b) < 1.0
    assert metrics.coverage(a) == pytest.approx(a[..., 3].sum(dtype=np.float64), rel=1e-6)
    half = a.copy()
    half[..., 3] *= 0.5
    assert metrics.coverage_error(half, a) == pytest.approx(-0.5)
    with pytest.raises(ValueError, match="shape"):
        metrics.rmse(a, b[:8])
    with pytest.raises(ValueError, match="NaN"):
        metrics.rmse(a, np.full_like(a, np.nan))


@pytest.mark.parametrize("scale", [1e200, 1e307])
def test_rmse_of_huge_finite_images_is_finite_and_exact(scale):
    """Finite inputs whose squares (1e200) or even difference (1e307 - -1e307) overflow float64
    give the RMSE, not inf (the fuzz's metrics property met it as an overflow warning): the
    closed form, and the same images scaled to 1 carried back (relative 1e-12: a few roundings)."""
    a = np.zeros((4, 5, 4))
    a[0, 0, 0], a[1, 2, 3] = scale, -scale
    e = metrics.rmse(a, -a)
    assert np.isfinite(e)
    assert e == pytest.approx(2 * scale * np.sqrt(2 / a.size), rel=1e-12)
    assert e == pytest.approx(scale * metrics.rmse(a / scale, -a / scale), rel=1e-12)
