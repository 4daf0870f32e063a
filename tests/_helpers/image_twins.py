"""Plain numpy twins of the motionblur.image kernels, written from the papers' equations and
the documented filter geometry (float64 throughout). Used by tests/core/test_image*.py."""

from __future__ import annotations

import math

import numpy as np

EPS = 1e-12


def plan(direction, reach):
    dx, dy = float(direction[0]), float(direction[1])
    n = math.hypot(dx, dy)
    if n <= 0 or reach <= 0:
        return None
    transpose = abs(dy) > abs(dx)
    major, minor = (dy, dx) if transpose else (dx, dy)
    r = math.floor(reach * abs(major) / n)
    if r == 0:
        return None
    return transpose, minor / major, r


def box_rows(img, r):
    """Zero-padded mean of 2r+1 taps along axis 1 of (h, n, C)."""
    n = img.shape[1]
    p = np.pad(img, ((0, 0), (r + 1, r), (0, 0)))
    c = np.cumsum(p, axis=1)
    return (c[:, 2 * r + 1 : 2 * r + 1 + n] - c[:, :n]) / (2 * r + 1)


def glow_rows(a, w):
    """Eq. 10 along axis 1 of (h, n), zero outside."""
    if w == 0:
        return a.copy()
    n = a.shape[1]
    p = np.pad(a, ((0, 0), (w, w)))
    out = np.zeros_like(a)
    for k in range(-w, w + 1):
        wt = 1.0 - abs(k) / w
        out = np.maximum(out, wt * p[:, w + k : w + k + n])
    return np.maximum(out, a)


def shear(img, t):
    """Sheared rows j0.. of (h, w, C): S[j, x] = lerp of column x at y = j + x t."""
    h, w, _ = img.shape
    e = -(w - 1) * t
    j0 = math.floor(min(e, 0.0))
    j1 = math.floor(max(e, 0.0) + (h - 1)) + 1
    js = np.arange(j0, j1 + 1, dtype=np.float64)
    ys = js[:, None] + np.arange(w)[None, :] * t
    y0 = np.floor(ys)
    f = (ys - y0)[..., None]
    y0 = y0.astype(np.int64)
    p = np.pad(img, ((1, 2), (0, 0), (0, 0)))  # row y of img is row y + 1 of p
    cols = np.arange(w)[None, :]
    a = p[np.clip(y0 + 1, 0, h + 2), cols]
    b = p[np.clip(y0 + 2, 0, h + 2), cols]
    a = np.where(((y0 >= 0) & (y0 < h))[..., None], a, 0.0)
    b = np.where(((y0 + 1 >= 0) & (y0 + 1 < h))[..., None], b, 0.0)
    return (1 - f) * a + f * b, j0


def unshear(s, j0, t, h):
    rows, w, _ = s.shape
    js = np.arange(h)[:, None] - np.arange(w)[None, :] * t
    jf = np.floor(js)
    f = (js - jf)[..., None]
    i = jf.astype(np.int64) - j0
    p = np.pad(s, ((1, 2), (0, 0), (0, 0)))
    cols = np.arange(w)[None, :]
    a = np.where(((i >= 0) & (i < rows))[..., None], p[np.clip(i + 1, 0, rows + 2), cols], 0.0)
    b = np.where(((i + 1 >= 0) & (i + 1 < rows))[..., None], p[np.clip(i + 2, 0, rows + 2), cols], 0.0)
    return (1 - f) * a + f * b


def directional(img, pl, rowfn):
    """Runs rowfn((h, n, C) -> (h, n, C')) along the plan's direction (transpose / shear)."""
    transpose, t, _ = pl
    x = np.swapaxes(img, 0, 1) if transpose else img
    if t == 0.0:
        y = rowfn(x)
    else:
        s, j0 = shear(x, t)
        y = unshear(rowfn(s), j0, t, x.shape[0])
    return np.swapaxes(y, 0, 1) if transpose else y


def box_blur(rgba, direction, length):
    img = rgba.astype(np.float64)
    pl = plan(direction, length / 2)
    if pl is None:
        return img
    return directional(img, pl, lambda x: box_rows(x, pl[2]))


def glow(alpha, direction, width):
    a = alpha.astype(np.float64)
    pl = plan(direction, width)
    if pl is None:
        return a
    g = directional(a[..., None], pl, lambda x: glow_rows(x[..., 0], pl[2])[..., None])[..., 0]
    return np.maximum(g, a) if pl[1] != 0 else g


def finish(blur, g, base=None, mode=None):
    ab = blur[..., 3]
    s = np.where(ab > EPS, g / np.where(ab > EPS, ab, 1.0), 0.0)
    sub = blur * s[..., None]
    sub[..., 3] = g
    if mode is None:
        return sub
    if mode == "over":
        return sub + (1 - g)[..., None] * base
    return base + (1 - base[..., 3:4]) * sub


def opaque_blur(rgba, direction, length, mode=None, base=None):
    img = rgba.astype(np.float64)
    b = img if base is None else base.astype(np.float64)
    pl = plan(direction, length / 2)
    if pl is None:
        return finish(img, img[..., 3], b, mode)
    r = pl[2]

    def rows(x):
        return np.concatenate([box_rows(x, r), glow_rows(x[..., 3], r)[..., None]], axis=-1)

    five = directional(img, pl, rows)
    g = five[..., 4]
    if pl[1] != 0:
        g = np.maximum(g, img[..., 3])
    return finish(five[..., :4], g, b, mode)


# --- pyramids


def analyse(img):
    h, w, c = img.shape
    ch, cw = (h + 1) // 2, (w + 1) // 2
    p = np.pad(img, ((1, 2 * ch + 2 - h), (1, 2 * cw + 2 - w), (0, 0)))
    tmp = sum(p[:, a : a + 2 * cw : 2] for a in range(4)) / 4.0
    return sum(tmp[b : b + 2 * ch : 2] for b in range(4)) / 4.0


def expand(c, h, w):
    def axis(x, n):
        m = x.shape[0]
        idx = np.arange(n)
        i = idx // 2
        j = np.where(idx % 2 == 0, i - 1, i + 1)
        near = x[i]
        ok = (j >= 0) & (j < m)
        far = np.where(ok.reshape(-1, *([1] * (x.ndim - 1))), x[np.clip(j, 0, m - 1)], 0.0)
        return 0.75 * near + 0.25 * far

    t = np.swapaxes(axis(np.swapaxes(c, 0, 1), w), 0, 1)
    return axis(t, h)


def pyramid(img, levels):
    p = [img.astype(np.float64)]
    for _ in range(levels):
        p.append(analyse(p[-1]))
    return p


def pyramid_blur(rgba, levels):
    p = pyramid(rgba, levels)
    cur = p[-1]
    for lvl in range(levels - 1, -1, -1):
        cur = expand(cur, *p[lvl].shape[:2])
    return cur


def pyramid_glow(alpha, levels):
    p = pyramid(alpha[..., None], levels)
    cur = p[-1]
    for lvl in range(levels - 1, -1, -1):
        e = expand(cur, *p[lvl].shape[:2])
        a = p[lvl]
        cur = e + a - e * a
    return cur[..., 0]


def pyramid_opaque_blur(rgba, levels):
    return finish(pyramid_blur(rgba, levels), pyramid_glow(rgba[..., 3].astype(np.float64), levels))


# --- depth of field


def disc_radius(levels):
    """The disc with the second moment of the ``levels``-level pyramid blur."""
    return math.sqrt(2 * 4.0**levels - 1) if levels else 0.0


def layer_depth(i, zf, r_inf):
    if i == 0:
        return zf
    r = disc_radius(abs(i))
    if i < 0:
        return zf / (1 + r / r_inf)
    return zf / (1 - r / r_inf) if r < r_inf else math.inf


def matte(d, z, front, back):
    za, zb, zc, zd = z
    with np.errstate(invalid="ignore", divide="ignore"):
        up = np.where(d <= za, 0.0, (d - za) / (zb - za))
        down = 1.0 if math.isinf(zd) else (zd - d) / (zd - zc)
        wt = np.where(d < zb, 1.0 if front else up, np.where(d <= zc, 1.0, np.where(d >= zd, 0.0, down)))
        if back:
            wt = np.where(d > zc, 1.0, wt)
    return np.nan_to_num(wt)


def depth_of_field(rgba, depth, focal_depth, focal_length, f_number, yfov, layers=5):
    h = rgba.shape[0]
    r_inf = h / (2 * focal_depth * math.tan(yfov / 2)) * focal_length / (2 * f_number)
    lo = -(layers // 2)
    ids = [
        i for i in range(lo, lo + layers) if i == lo or math.isfinite(layer_depth(i - 1, focal_depth, r_inf))
    ]
    img = rgba.astype(np.float64)
    d = depth.astype(np.float64)
    buf = np.zeros_like(img)
    for k in range(len(ids) - 1, -1, -1):
        i = ids[k]
        z = [layer_depth(i + o, focal_depth, r_inf) for o in (-2, -1, 0, 1)]
        wt = matte(d, z, k == 0, k == len(ids) - 1)
        sub = np.concatenate([img[..., :3] * wt[..., None], wt[..., None]], axis=-1)
        if i != 0:
            sub = pyramid_opaque_blur(sub, abs(i))
        buf = sub + (1 - sub[..., 3:4]) * buf
    return buf


def push_pull(rgba, levels):
    p = pyramid(rgba, levels)
    cur = p[-1]
    for lvl in range(levels - 1, -1, -1):
        a = p[lvl]
        cur = a + (1 - a[..., 3:4]) * expand(cur, *a.shape[:2])
    return cur


def lens_kernel_radius(j):
    return 0.0 if j == 0 else math.sqrt(2.0) if j == 1 else disc_radius(j - 1)


def lens_kernel(x, j):
    if j == 0:
        return x
    if j == 1:
        p = np.pad(x, ((1, 1), (1, 1), (0, 0)))
        r = 0.25 * p[:, :-2] + 0.5 * p[:, 1:-1] + 0.25 * p[:, 2:]
        return 0.25 * r[:-2] + 0.5 * r[1:-1] + 0.25 * r[2:]
    return pyramid_blur(x, j - 1)


def lens_blur(rgba, depth, aperture, focus_distance, yfov):
    """src/image/lens.rs, float64: sub-images by circle of confusion, blended far to near."""
    h, w = depth.shape
    img = rgba.astype(np.float64)
    r_inf = h * aperture / (2 * focus_distance * math.tan(yfov / 2))
    d = depth.astype(np.float64)
    with np.errstate(divide="ignore"):
        s = np.where(np.isinf(d), r_inf, r_inf * (1 - focus_distance / d))
    top = 0
    while top < 9 and lens_kernel_radius(top) < np.abs(s).max():
        top += 1
    radii = np.array([lens_kernel_radius(j) for j in range(top + 1)])
    a = np.abs(s)
    k = np.searchsorted(radii, a, side="right") - 1
    hi = radii[np.minimum(k + 1, top)]
    lo = radii[k]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(k < top, np.clip((a * a - lo * lo) / (hi * hi - lo * lo), 0, 1), 0.0)
    pos = np.where(s >= 0, top - k, top + 1 + k)
    ones = [lens_kernel(np.ones((h, w, 1)), j) for j in range(top + 1)]

    def nblur(x, j):
        return lens_kernel(x, j) / ones[j]

    buf = np.zeros_like(img)
    for q in range(2 * top + 2):
        m = pos == q
        if not m.any():
            continue
        kq = top - q if q <= top else q - top - 1
        ext = push_pull(img * m[..., None], kq + 2) * img[..., 3:4]
        pa = np.where(m[..., None], img * (1 - t[..., None]), np.where((pos > q)[..., None], ext, 0.0))
        sub = nblur(pa, kq)
        if kq < top and (t[m] > 0).any():
            sub = sub + nblur(img * (m * t)[..., None], kq + 1)
        sub = sub / np.maximum(sub[..., 3:4], 1.0)
        buf = sub + (1 - sub[..., 3:4]) * buf
    n, lv = max(h, w), 0
    while n > 1:
        n, lv = -(-n // 2), lv + 1
    fill = push_pull(buf, lv)
    deficit = img[..., 3:4] - buf[..., 3:4]
    with np.errstate(invalid="ignore", divide="ignore"):
        add = np.where((deficit > 0) & (fill[..., 3:4] > 1e-12), deficit / fill[..., 3:4], 0.0)
    buf = buf + add * fill
    buf[..., 3] = np.minimum(buf[..., 3], 1.0)
    return buf


# --- camera blur


def camera_velocity(depth, camera, previous):
    """Unprojects through inv(projection) and inv(view), reprojects with the previous camera."""
    h, w = depth.shape
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    nx = 2 * (x + 0.5) / w - 1
    ny = 1 - 2 * (y + 0.5) / h
    clip = np.stack([nx, ny, -np.ones_like(nx), np.ones_like(nx)], -1)
    v = clip @ np.linalg.inv(camera.projection).T
    v = v[..., :3] / v[..., 3:4]  # a point on the near plane, view space
    d = depth.astype(np.float64)[..., None]
    dirn = v / -v[..., 2:3]  # view-space point at depth 1
    inf = np.isinf(d)
    pt = np.concatenate([np.where(inf, dirn, dirn * np.where(inf, 1.0, d)), np.where(inf, 0.0, 1.0)], -1)
    world = pt @ np.linalg.inv(camera.view).T
    q = world @ (previous.projection @ previous.view).T
    with np.errstate(divide="ignore", invalid="ignore"):
        px = (q[..., 0] / q[..., 3] + 1) * 0.5 * w
        py = (1 - q[..., 1] / q[..., 3]) * 0.5 * h
    vel = np.stack([x + 0.5 - px, y + 0.5 - py], -1)
    return np.where((q[..., 3] > 0)[..., None], vel, 0.0)


def velocity_blur(rgba, velocity, samples):
    img = rgba.astype(np.float64)
    h, w, _ = img.shape
    if samples == 1:
        return img
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    acc = np.zeros_like(img)
    for s in range(samples):
        t = s / (samples - 1) - 0.5
        px = x + velocity[..., 0] * t
        py = y + velocity[..., 1] * t
        x0, y0 = np.floor(px), np.floor(py)
        fx, fy = (px - x0)[..., None], (py - y0)[..., None]
        x0, y0 = x0.astype(np.int64), y0.astype(np.int64)

        def at(xx, yy):
            return img[np.clip(yy, 0, h - 1), np.clip(xx, 0, w - 1)]

        top = at(x0, y0) + fx * (at(x0 + 1, y0) - at(x0, y0))
        bot = at(x0, y0 + 1) + fx * (at(x0 + 1, y0 + 1) - at(x0, y0 + 1))
        acc += top + fy * (bot - top)
    out = acc / samples
    still = (velocity[..., 0] == 0) & (velocity[..., 1] == 0)
    return np.where(still[..., None], img, out)


def _jitter(x: int, y: int) -> float:
    m = 0xFFFFFFFF
    h = ((x * 0x8DA6B343) & m) ^ ((y * 0xD8163841) & m)
    h ^= h >> 13
    h = (h * 0x5BD1E995) & m
    h ^= h >> 15
    return (h >> 8) / float(1 << 24)


def reconstruct_twin(rgba, depth, velocity, samples=16, tile=8, soft_depth=0.02):
    """Plain-Python twin of ``src/image/reconstruct/`` (McGuire 2012 / Guertin 2014 gather,
    the formulas of its module docs), float64; for small images."""
    h, w = depth.shape
    half = 0.5 * velocity.astype(np.float64)
    ln = np.hypot(half[..., 0], half[..., 1])
    scale = np.where(ln > tile, tile / np.maximum(ln, 1e-300), 1.0)
    half = half * scale[..., None]
    ln = np.hypot(half[..., 0], half[..., 1])
    tx, ty = -(-w // tile), -(-h // tile)
    tiles = np.zeros((ty, tx, 2))
    for by in range(ty):
        for bx in range(tx):
            best = np.zeros(2)
            for y in range(by * tile, min((by + 1) * tile, h)):
                for x in range(bx * tile, min((bx + 1) * tile, w)):
                    if ln[y, x] ** 2 > best @ best:
                        best = half[y, x]
            tiles[by, bx] = best
    nmax = np.zeros_like(tiles)
    for by in range(ty):
        for bx in range(tx):
            best = np.zeros(2)
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    y, x = by + dy, bx + dx
                    if 0 <= y < ty and 0 <= x < tx and tiles[y, x] @ tiles[y, x] > best @ best:
                        best = tiles[y, x]
            nmax[by, bx] = best
    out = np.zeros((h, w, 4))
    col = rgba.astype(np.float64)
    for y in range(h):
        for x in range(w):
            n, c = nmax[y // tile, x // tile], half[y, x]
            rn, rc = np.hypot(*n), np.hypot(*c)
            if max(rn, rc) < 0.5:
                out[y, x] = col[y, x]
                continue
            zx = float(depth[y, x])
            fg, bg = np.zeros(4), np.zeros(4)
            acc = [0.0, 0.0, 0.0]  # wf, wb, taps

            def tap(yy, xx, d, zx=zx, rc=rc, fg=fg, bg=bg, acc=acc):
                zy = float(depth[yy, xx])
                near = min(zx, zy)
                f = 0.5 if zx == zy else float(np.clip(0.5 - (zy - zx) / (soft_depth * near), 0, 1))
                a = f * np.clip(ln[yy, xx] - d + 1, 0, 1)
                b = (1 - f) * np.clip(rc - d + 1, 0, 1)
                fg[:] += a * col[yy, xx]
                bg[:] += b * col[yy, xx]
                acc[0] += a
                acc[1] += b
                acc[2] += 1

            tap(y, x, 0.0)
            pairs = samples // 2
            both = rc >= 0.5 and rn >= 0.5
            # one jitter a run of eight pixels of a row (from the tile's left edge); along n a
            # tap is the run's first pixel's, moved along the row
            x0 = x - (x % tile) % 8
            j = _jitter(x0, y)
            # a moving pixel's own direction is its run's: the run's first moving pixel's half
            # velocity (the run ends at the tile's right edge, eight pixels at most); along it
            # too a tap is the run's first pixel's, moved along the row
            end = min((x0 // tile + 1) * tile, w, x0 + 8)
            first = next((k for k in range(x0, end) if ln[y, k] >= 0.5), x)
            cr = half[y, first]
            for p in range(pairs):
                if both and p % 2 == 1:
                    dvec, r, q, m, a = cr, float(np.hypot(*cr)), p // 2, pairs // 2, x0
                elif both:
                    dvec, r, q, m, a = n, rn, p // 2, pairs - pairs // 2, x0
                elif rn >= 0.5:
                    dvec, r, q, m, a = n, rn, p, pairs, x0
                else:
                    dvec, r, q, m, a = c, rc, p, pairs, x
                t = (q + j) / max(m, 1)
                for s in (-1.0, 1.0):
                    px, py = a + 0.5 + s * t * dvec[0], y + 0.5 + s * t * dvec[1]
                    sx, sy = int(np.floor(px)) + x - a, int(np.floor(py))
                    if sx < 0 or sy < 0 or sx >= w or sy >= h:
                        continue
                    d = min(np.hypot(sx - x, sy - y), t * r)
                    tap(sy, sx, d)
            wf, wb, taps = acc
            fill = float(np.clip(1 - (wf + wb) / taps, 0, 1))
            back = bg / wb if wb > 0 else col[y, x]
            out[y, x] = (fg + bg) / taps + back * fill
    return out.astype(np.float32)
