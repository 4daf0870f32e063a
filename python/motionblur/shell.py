"""Blur shells for deforming meshes (Jones and Keyser): BlurShell and the silhouette of motion."""

from __future__ import annotations

__all__: list[str] = []
