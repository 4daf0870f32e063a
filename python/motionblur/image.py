"""Image-space blur kernels (Kraus's opaque image blur, pyramids, depth of field, Chapman's camera blur).

Images are float32 (H,W,4), linear RGB, premultiplied alpha, row 0 at the top.
"""

from __future__ import annotations

__all__: list[str] = []
