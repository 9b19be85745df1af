"""cdef_from_headers.py: the block bindings' declarations come from the headers as they are.

A header with what the core's headers hold (a guard, C library includes, a header of the
same folder, numeric macros, an enum, a struct, a static inline function, a static
assertion) becomes declarations cffi accepts; an edit of the header shows in them.
"""

import cffi
from cdef_from_headers import cdef

BLOCK_H = """\
#ifndef BLOCK_H
#define BLOCK_H
#include <stdbool.h>
#include <stdint.h>
#include "status.h"
#define BLOCK_N 4
#define BLOCK_MASK 0x10u
#define BLOCK_GAIN 0.5f
#define BLOCK_TWICE(x) (2 * (x))
typedef enum block_kind { BLOCK_A = 0, BLOCK_B = 7 } block_kind_t;
typedef struct block { float x[BLOCK_N]; uint8_t flags; bool on; } block_t;
_Static_assert(sizeof(float) == 4, "float32");
status_t block_step(block_t *b, const float in[BLOCK_N]);
static inline float block_first(const block_t *b) { return b->x[0]; }
#endif
"""
STATUS_H = "#ifndef STATUS_H\n#define STATUS_H\ntypedef enum { OK = 0, ERR = -1 } status_t;\n#endif\n"


def _folder(tmp_path, block_h=BLOCK_H):
    (tmp_path / "block.h").write_text(block_h)
    (tmp_path / "status.h").write_text(STATUS_H)
    return tmp_path


def test_a_header_becomes_declarations_cffi_accepts(tmp_path):
    text = cdef(_folder(tmp_path), ("block.h",))
    assert "#define BLOCK_N ..." in text and "#define BLOCK_MASK ..." in text
    assert "static const float BLOCK_GAIN;" in text
    assert "BLOCK_TWICE" not in text and "BLOCK_H" not in text     # function-like, guard
    assert "status_t block_step(block_t *b, const float in[4]);" in text
    assert "float block_first(const block_t *b);" in text and "return" not in text
    assert "_Static_assert" not in text and "#include" not in text
    assert text.index("status_t;") < text.index("block_step")       # included header first
    ffi = cffi.FFI()
    ffi.cdef(text)
    assert ffi.sizeof("block_t") == 4 * 4 + 1 + 1 + 2                 # float x[4], flags, on
    assert ffi.typeof("block_kind_t").relements["BLOCK_B"] == 7


def test_an_edited_header_changes_the_declarations(tmp_path):
    before = cdef(_folder(tmp_path), ("block.h",))
    edited = BLOCK_H.replace("BLOCK_B = 7", "BLOCK_B = 8").replace("bool on;", "bool on; float k;")
    after = cdef(_folder(tmp_path, edited), ("block.h",))
    assert "BLOCK_B = 7" in before and "BLOCK_B = 8" in after
    assert "float k;" in after and "float k;" not in before
