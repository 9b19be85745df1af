"""C extensions of silbridge, built by the package build itself.

Each extension is listed with its explicit sources (as Crazyflie's Python
bindings do), so what is compiled is visible here; an extension whose
sources are not present yet is skipped, never half-built.
"""

import glob
import os

import numpy
from setuptools import Extension, setup

CFLAGS = ["-std=c11", "-O2", "-Wall", "-Wextra", "-Wno-missing-field-initializers"]


def sources(*patterns):
    out = []
    for pattern in patterns:
        out.extend(sorted(glob.glob(pattern)))
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

core_src = sources("fc_sil/core/*.c", "fc_sil/ext/*.c")
if core_src:
    extensions.append(
        Extension(
            "silbridge.fc_sil._core",
            core_src,
            include_dirs=["fc_sil/core", "shm/include"],
            depends=sources("fc_sil/core/*.h", "fc_sil/core/*.def", "fc_sil/ext/*.h",
                            "shm/include/*.h"),  # rebuild on header / parameter edits
            extra_compile_args=CFLAGS,
            libraries=["m"],
        )
    )

# The blocks of the core one by one, for fc_sil/blocks.py and the tests only: a module of
# its own, so the flight's _core carries none of it. It compiles the core's sources too.
blocks_src = sources("fc_sil/ext/blocks/*.c")
if blocks_src:
    extensions.append(
        Extension(
            "silbridge.fc_sil._blocks",
            sources("fc_sil/core/*.c") + blocks_src,
            include_dirs=["fc_sil/core", numpy.get_include()],
            depends=sources("fc_sil/core/*.h", "fc_sil/core/*.def", "fc_sil/ext/blocks/*.h"),
            extra_compile_args=CFLAGS,
            libraries=["m"],
        )
    )

# stepmodule.c (the Python type), step_run.c (the step), step_config.c, step_maths.c
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
            libraries=["m"],
        )
    )

# SILBRIDGE_EXT=ring (or core, blocks, step) builds one extension only: handy while another
# extension's sources are mid-edit (`SILBRIDGE_EXT=ring python setup.py build_ext --inplace`).
only = os.environ.get("SILBRIDGE_EXT")
if only:
    extensions = [e for e in extensions if e.name.rsplit(".", 1)[-1].lstrip("_") == only]

setup(ext_modules=extensions)
