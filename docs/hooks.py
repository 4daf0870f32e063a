"""mkdocs hooks.

- The page of methods is written from the registry at build time, from the same signatures and
  docstrings as ``help(motionblur.render)``, so the two cannot drift.
- The benchmarks page shows the tables of the last ``make bench`` run (``out/bench/**/*.md``,
  written by ``benches/bench_*.py`` and ``python -m motionblur bench``) when there is one, and
  otherwise says how to make them, so that a fresh clone builds with ``--strict``.
"""

from __future__ import annotations

import re
from pathlib import Path

PLACEHOLDER = "<!-- render-methods -->"
BENCH_PLACEHOLDER = "<!-- bench-results -->"
#: The report's own table first, then each benchmark script's, by name.
FIRST = "results.md"


def on_page_markdown(markdown: str, page, config, files) -> str:
    if BENCH_PLACEHOLDER in markdown:
        root = Path(config["config_file_path"]).resolve().parent
        markdown = markdown.replace(BENCH_PLACEHOLDER, bench_results(root / "out" / "bench", root))
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


def bench_results(folder: Path, root: Path) -> str:
    """The Markdown tables under ``folder`` (``out/bench``), each under a heading naming its file,
    its own headings moved below that one; or how to produce them when there are none."""
    found = sorted(
        folder.rglob("*.md"),
        key=lambda p: (p.name != FIRST, len(p.relative_to(folder).parts), str(p.relative_to(folder))),
    )
    if not found:
        return (
            '!!! info "No benchmark output in this build"\n'
            "    This page shows the tables of the last benchmark run when the site is built after one.\n"
            "    Run `make bench` (every script under `benches/` and the speed-against-error report,\n"
            "    about half an hour on 2 cores; `python -m motionblur bench --quick` for the report\n"
            "    alone) and then `make docs`: the tables in `out/bench/**/*.md` appear here.\n"
        )
    parts = [
        "## The last run's tables",
        "",
        f"Read from `out/bench/` when this site was built ({len(found)} files; the plots are beside them "
        "there, `pareto_<scene>.png`, `scaling_*.png`).",
        "",
    ]
    for path in found:
        text = path.read_text()
        text = re.sub(r"^(#{1,6}) ", lambda m: "#" * min(6, len(m.group(1)) + 3) + " ", text, flags=re.M)
        parts += [f"### `{path.relative_to(root).as_posix()}`", "", text.strip(), ""]
    return "\n".join(parts)
