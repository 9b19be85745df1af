"""The lockstep hand-off's choice (shm/src/handoff_choice.c), bound for the tests by cffi.

The declarations come from shm/include/sb_handoff_choice.h through the same header reader as
the FC core's bindings (tests/fc_sil/cdef_from_headers.py); the compiled source is the very
file the _ring extension builds. Built once per source version into build/cffi/<key>
(a file lock lets parallel pytest processes share it).
"""

from __future__ import annotations

import fcntl
import hashlib
import importlib.util
import shutil
import sys
import tempfile
from pathlib import Path

import cffi

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "fc_sil"))
from cdef_from_headers import cdef  # noqa: E402  (the FC core tests' header reader)

MODULE = "_shm_handoff_cffi"
CACHE = ROOT / "build" / "cffi"
INCLUDE = ROOT / "shm" / "include"
HEADER = "sb_handoff_choice.h"
SOURCE = ROOT / "shm" / "src" / "handoff_choice.c"


def _load():
    declarations = cdef(INCLUDE, (HEADER,))
    h = hashlib.sha256()
    for part in (declarations, cffi.__version__, (INCLUDE / HEADER).read_text(),
                 SOURCE.read_text(), sys.version):
        h.update(part.encode())
    target = CACHE / f"handoff-{h.hexdigest()[:16]}"
    CACHE.mkdir(parents=True, exist_ok=True)
    with open(CACHE / ".lock-handoff", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not target.is_dir():
            ffi = cffi.FFI()
            ffi.cdef(declarations)
            ffi.set_source(MODULE, f'#include "{HEADER}"\n', sources=[str(SOURCE)],
                           include_dirs=[str(INCLUDE)], extra_compile_args=["-std=c11", "-O2"])
            with tempfile.TemporaryDirectory(dir=CACHE) as scratch:
                built = Path(ffi.compile(tmpdir=scratch))
                target.mkdir()
                shutil.move(str(built), target / built.name)
        path = next(target.glob(MODULE + ".*"))
        spec = importlib.util.spec_from_file_location(MODULE, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    return module.ffi, module.lib


ffi, lib = _load()
