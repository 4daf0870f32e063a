"""Object-space geometry: meshes, contour edges, silhouettes of motion, motion volumes, contour tables."""

from __future__ import annotations

__all__: list[str] = []
