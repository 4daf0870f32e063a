"""mkdocs hook: the page of methods is written from the registry at build time, from the same
signatures and docstrings as ``help(motionblur.render)``, so the two cannot drift."""

from __future__ import annotations

PLACEHOLDER = "<!-- render-methods -->"


def on_page_markdown(markdown: str, page, config, files) -> str:
    if PLACEHOLDER not in markdown:
        return markdown
    from motionblur.render import METHODS, _options_paragraph, _parameters

    out = []
    for name in sorted(METHODS):
        spec = METHODS[name]
        sig = ", ".join(
            f"{p.name}={p.default!r}" if p.default is not p.empty else p.name
            for p in _parameters(spec.fn).values()
        )
        out += [f"### `{name}`", "", f'`render(scene, "{name}", {sig})`: {spec.doc}', ""]
        if spec.needs:
            out += [f"Applies to scenes with {spec.needs}.", ""]
        para = _options_paragraph(spec.fn.__doc__ or "")
        if para:
            out += [f"**Options:** {para}", ""]
    return markdown.replace(PLACEHOLDER, "\n".join(out))
