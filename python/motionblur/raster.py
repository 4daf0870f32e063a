"""The CPU software rasterizer: Camera, Draw, rasterize, Frame."""

from __future__ import annotations

__all__: list[str] = []
