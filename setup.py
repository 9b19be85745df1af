"""C extensions of silbridge, built by the package build itself.

Each extension is listed with its explicit sources (as Crazyflie's Python
bindings do), so what is compiled is visible here; an extension whose
sources are not present yet is skipped, never half-built. The tests read the
portable core's declaration (CORE_*) from this file too, for the block
bindings they generate from its headers (tests/fc_sil/core_cffi.py): setup()
runs only when this file runs as the build script.
"""

import glob
import os

import numpy
from setuptools import Extension, setup

CFLAGS = ["-std=c11", "-O2", "-Wall", "-Wextra", "-Wno-missing-field-initializers"]
HERE = os.path.dirname(os.path.abspath(__file__))


def sources(*patterns):
    """Files matching the patterns, relative to this file's folder, whatever the cwd."""
    out = []
    for pattern in patterns:
        out.extend(sorted(glob.glob(pattern, root_dir=HERE)))
    return out


extensions = []

ring_src = sources("shm/src/*.c")
if ring_src:
    extensions.append(
        Extension(
            "silbridge.shm._ring",
            ring_src,
            include_dirs=["shm/include", numpy.get_include()],
            depends=sources("shm/include/*.h", "shm/src/*.h"),  # rebuild on header edits
            extra_compile_args=CFLAGS,
            libraries=["rt"],
        )
    )

# The portable flight-controller core: no Python, no OS. The flight's _core compiles it
# with its CPython shim (fc_sil/ext); the tests compile the same list into bindings
# generated from its headers with cffi (a test extra), so no package module binds a block.
CORE_SOURCES = sources("fc_sil/core/*.c")
CORE_INCLUDE_DIRS = ["fc_sil/core"]
CORE_DEPENDS = sources("fc_sil/core/*.h", "fc_sil/core/*.def")  # headers, parameter table
CORE_LIBRARIES = ["m"]

core_src = CORE_SOURCES + sources("fc_sil/ext/*.c")
if core_src:
    extensions.append(
        Extension(
            "silbridge.fc_sil._core",
            core_src,
            include_dirs=CORE_INCLUDE_DIRS + ["shm/include"],
            depends=CORE_DEPENDS + sources("fc_sil/ext/*.h", "shm/include/*.h"),
            extra_compile_args=CFLAGS,
            libraries=CORE_LIBRARIES,
        )
    )

# stepmodule.c (the Python type), step_run.c (the CPython shim of one step), sensor_stage.c
# (the pure-C sensor stage), battery.c (the pure-C battery pack the stage reports) and
# step_battery.c (its Kernel methods), step_config.c, step_forces.c, step_maths.c, step_json.c
step_src = sources("bridge/src/*.c")
if step_src:
    extensions.append(
        Extension(
            "silbridge.bridge._step",
            step_src,
            include_dirs=["bridge/src", "shm/include"],
            depends=sources("bridge/src/*.h", "shm/include/*.h"),
            # No FMA contraction: the kernel must give the Python reference's exact doubles.
            extra_compile_args=CFLAGS + ["-ffp-contract=off"],
            libraries=["m", "dl"],
        )
    )

# SILBRIDGE_EXT=ring (or core, step) builds one extension only: handy while another
# extension's sources are mid-edit (`SILBRIDGE_EXT=ring python setup.py build_ext --inplace`).
only = os.environ.get("SILBRIDGE_EXT")
if only:
    extensions = [e for e in extensions if e.name.rsplit(".", 1)[-1].lstrip("_") == only]

if __name__ == "__main__":      # the build (pip's backend runs it so too), not a reader
    setup(ext_modules=extensions)
