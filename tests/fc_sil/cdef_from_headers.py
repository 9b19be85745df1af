"""The cffi declarations (cdef) of C headers, read from the headers themselves.

cffi's cdef takes plain C declarations: no preprocessor and no function bodies. So the
headers go through the C preprocessor (gcc, with their own includes expanded and empty
stand-ins for the C library's headers), then through pycparser, the C parser cffi itself
uses; what the given folder's headers declare is printed back as declarations. A static
inline function becomes a plain declaration (API mode calls it through the header), and
each object-like macro with a number becomes a constant the compiler evaluates. Nothing
is copied from a header by hand, so a changed header changes the bindings.
"""

from __future__ import annotations

import re
import subprocess
import tempfile
from pathlib import Path

import pycparser
from cffi.commontypes import COMMON_TYPES
from pycparser import c_ast, c_generator

# gcc's line markers say which file the lines after them come from.
_LINE_MARKER = re.compile(r'# \d+ "([^"]*)"')
_DEFINE = re.compile(r"#define (\w+) (.+)$")     # object-like and with a value
_INT = re.compile(r"\(?-?(0[xX][0-9a-fA-F]+|\d+)[uUlL]*\)?")
_FLOAT = re.compile(r"\(?-?(\d+\.\d*|\.\d+)([eE][-+]?\d+)?([fF]?)\)?")
_SYSTEM_INCLUDE = re.compile(r"#include\s*<([\w/]+\.h)>")

# The type names cffi knows without a declaration (stdint.h, stdbool.h, stddef.h...): the
# parser is told they are types, and the declarations keep them by name.
_PRELUDE = "".join(f"typedef int {name};\n" for name in COMMON_TYPES if name.isidentifier())


def _preprocess(folder: Path, headers: tuple[str, ...]) -> str:
    """The headers through gcc -E, macros kept (-dD), C library headers empty."""
    wanted = {m for h in folder.glob("*.h") for m in _SYSTEM_INCLUDE.findall(h.read_text())}
    source = _PRELUDE + "".join(f'#include "{h}"\n' for h in headers)
    with tempfile.TemporaryDirectory() as stubs:
        for name in wanted:
            (Path(stubs) / name).parent.mkdir(parents=True, exist_ok=True)
            (Path(stubs) / name).touch()
        return subprocess.run(["gcc", "-E", "-std=c11", "-dD", "-nostdinc", "-isystem", stubs,
                               "-I", str(folder), "-"], input=source, capture_output=True,
                              text=True, check=True).stdout


def _split(preprocessed: str, folder: Path) -> tuple[str, list[str]]:
    """(C text for the parser, line markers kept; the folder's #define lines)."""
    text, defines, current = [], [], ""
    for line in preprocessed.splitlines():
        marker = _LINE_MARKER.match(line)
        if marker:
            current = marker.group(1)
        elif line.startswith("#"):
            if line.startswith("#define") and Path(current).parent == folder:
                defines.append(line)
            line = ""                                  # keep the line numbering
        text.append(line)
    return "\n".join(text), defines


def _constant(define: str) -> str | None:
    """cffi's declaration of a numeric macro; None for a guard or an expression."""
    m = _DEFINE.match(define.strip())
    if m is None:
        return None
    name, value = m.group(1), m.group(2).strip()
    if _INT.fullmatch(value):
        return f"#define {name} ..."                  # integer: the compiler gives the value
    number = _FLOAT.fullmatch(value)
    if number:
        return f"static const {'float' if number.group(3) else 'double'} {name};"
    return None


def _declaration(node: c_ast.Node, gen: c_generator.CGenerator) -> str | None:
    if isinstance(node, c_ast.FuncDef):               # static inline: its prototype
        node = node.decl
        node.storage = [s for s in node.storage if s != "static"]
        node.funcspec = []
    if isinstance(node, (c_ast.Decl, c_ast.Typedef)):
        return gen.visit(node) + ";"
    return None                                        # _Static_assert, pragmas


def cdef(folder: Path, headers: tuple[str, ...]) -> str:
    """The cdef of `headers` (names in `folder`) and of the folder's headers they include."""
    folder = folder.resolve()
    text, defines = _split(_preprocess(folder, headers), folder)
    tree = pycparser.CParser().parse(text, "<headers>")
    gen = c_generator.CGenerator()
    ours = [node for node in tree.ext if Path(node.coord.file).parent == folder]
    lines = [c for c in map(_constant, defines) if c is not None]
    lines += [d for d in (_declaration(node, gen) for node in ours) if d is not None]
    return "\n".join(lines) + "\n"
