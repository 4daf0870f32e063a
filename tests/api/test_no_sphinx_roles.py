"""The docstrings use one cross-reference form, the one mkdocstrings renders ([`render`][motionblur.render.render]); a
Sphinx role such as :func:`render` would show as raw text on the API pages."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ROLE = re.compile(r":(func|class|data|meth|mod|attr|exc|obj):`")


def test_the_package_has_no_sphinx_roles():
    left = [
        f"{p.relative_to(ROOT)}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0)}"
        for p in sorted((ROOT / "python" / "motionblur").rglob("*.py"))
        for text in [p.read_text()]
        for m in ROLE.finditer(text)
    ]
    assert not left, "Sphinx roles (write [`name`][motionblur.path] instead):\n" + "\n".join(left)
