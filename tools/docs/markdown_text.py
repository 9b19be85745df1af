"""Plain text made safe for the Markdown of the generated pages (Python-Markdown, as mkdocs
reads it). Help texts carry characters Markdown would act on: `ours|ardupilot|px4` would
split a table cell, `*`, `_` and `[...]` would turn into emphasis or links, `<...>` into HTML.
"""

from __future__ import annotations

import html

# Backslash escapes Python-Markdown honours (its ESCAPED_CHARS, plus '|' from the tables
# extension); '<', '>' and '&' become entities, which every Markdown passes through.
_BACKSLASHED = set("\\`*_[]|#")
_ENTITIES = {"<": "&lt;", ">": "&gt;", "&": "&amp;"}


def cell(text: str) -> str:
    """Text shown literally inside a table cell or a paragraph, on one line; `quoted`
    commands in it stay code spans."""
    parts = " ".join(str(text).split()).split("`")
    if len(parts) % 2 == 0:                     # an unpaired backquote: all literal
        return _literal("`".join(parts))
    return "".join(code(p) if i % 2 else _literal(p) for i, p in enumerate(parts))


def _literal(text: str) -> str:
    out = []
    for ch in text:
        if ch in _BACKSLASHED:
            out.append("\\" + ch)
        else:
            out.append(_ENTITIES.get(ch, ch))
    return "".join(out)


def code(text: str) -> str:
    """An inline code span; a '|' inside it would still end a table cell, so none may occur."""
    text = str(text)
    if "|" in text or "`" in text or not text.strip():
        return _literal(text)
    return f"`{text}`"


def nowrap_code(text: str) -> str:
    """Code kept on one line: a flag such as `--attach-timeout S` must not break at its
    hyphens in a narrow table column. Raw HTML, so '|' is an entity, not a cell border."""
    return ('<code style="white-space:nowrap">'
            + html.escape(str(text), quote=False).replace("|", "&#124;") + "</code>")
