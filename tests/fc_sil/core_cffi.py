"""The flight-controller core's blocks, bound for the tests by cffi from their headers.

`ffi` and `lib` are a cffi module in API mode: the declarations come from the block
headers (cdef_from_headers.py) and the compiled sources are the core's own list, read
from setup.py (CORE_SOURCES, with the flags the flight's _core is built with), so the
tests run the very C the flight runs. cffi is a test extra: no package module binds a
block (tests/test_boundaries.py).

The module is built on first import in a test session and kept in build/cffi/<key>,
where the key hashes everything the build reads (sources, headers, flags, cffi and
Python versions): a later session loads it at once, and an edited header or source
builds anew. A file lock lets pytest processes running side by side share one build.
"""

from __future__ import annotations

import fcntl
import hashlib
import importlib.util
import runpy
import shutil
import sys
import sysconfig
import tempfile
from pathlib import Path

import cffi

from cdef_from_headers import cdef

ROOT = Path(__file__).resolve().parents[2]
MODULE = "_fc_core_cffi"
CACHE = ROOT / "build" / "cffi"

# The blocks the tests drive, by header; the headers they include come with them.
HEADERS = ("fc_filter.h", "fc_ins.h", "fc_mahony.h", "fc_attitude.h", "fc_shaper.h",
           "fc_rate_pid.h", "fc_trim.h", "fc_blend.h", "fc_mixer.h", "fc_fft.h")


def _core_declaration() -> dict:
    """setup.py's CORE_* and CFLAGS (setup() runs only as the build script)."""
    g = runpy.run_path(str(ROOT / "setup.py"), run_name="silbridge_setup_declarations")
    return dict(sources=[str(ROOT / s) for s in g["CORE_SOURCES"]],
                include_dirs=[str(ROOT / d) for d in g["CORE_INCLUDE_DIRS"]],
                depends=[str(ROOT / s) for s in g["CORE_DEPENDS"]],
                libraries=list(g["CORE_LIBRARIES"]), extra_compile_args=list(g["CFLAGS"]))


def _ffi(core: dict, declarations: str) -> cffi.FFI:
    ffi = cffi.FFI()
    ffi.cdef(declarations)
    ffi.set_source(MODULE, "".join(f'#include "{h}"\n' for h in HEADERS),
                   sources=core["sources"], include_dirs=core["include_dirs"],
                   libraries=core["libraries"], extra_compile_args=core["extra_compile_args"])
    return ffi


def _key(core: dict, declarations: str) -> str:
    h = hashlib.sha256()
    for part in (repr(core), declarations, cffi.__version__,
                 sysconfig.get_config_var("EXT_SUFFIX")):
        h.update(part.encode())
    for path in sorted(set(core["sources"] + core["depends"])):
        h.update(path.encode() + Path(path).read_bytes())
    return h.hexdigest()[:16]


def _build(ffi: cffi.FFI, target: Path) -> None:
    """Compile into a scratch folder, then move the finished module into place."""
    CACHE.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=CACHE) as scratch:
        built = Path(ffi.compile(tmpdir=scratch))
        target.mkdir()
        shutil.move(str(built), target / built.name)
    for old in CACHE.iterdir():                      # earlier keys: stale headers or sources
        if old.is_dir() and old != target and not old.name.startswith("tmp"):
            shutil.rmtree(old, ignore_errors=True)


def _load():
    core = _core_declaration()
    declarations = cdef(Path(core["include_dirs"][0]), HEADERS)
    target = CACHE / _key(core, declarations)
    CACHE.mkdir(parents=True, exist_ok=True)
    with open(CACHE / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not target.is_dir():
            _build(_ffi(core, declarations), target)
        path = next(target.glob(MODULE + ".*"))
        spec = importlib.util.spec_from_file_location(MODULE, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    sys.modules[MODULE] = module
    return module.ffi, module.lib


ffi, lib = _load()
