/*
 * ext_common.h - helpers shared by the files of the silbridge.fc_sil._core
 * extension (coremodule.c: the FlightCore object and record batches;
 * blockfuncs.c: per-block entry points the tests and thin wrappers use).
 */
#ifndef FC_EXT_COMMON_H
#define FC_EXT_COMMON_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#define PY_ARRAY_UNIQUE_SYMBOL silbridge_fc_core_ARRAY_API
#ifndef FC_EXT_IMPORT_ARRAY
#define NO_IMPORT_ARRAY
#endif
#include <numpy/arrayobject.h>

#include "fc_status.h"

/* The per-block functions (blockfuncs.c), appended to the module's methods. */
extern PyMethodDef fc_ext_block_methods[];

/* A writable, 8-byte aligned buffer of at least `size` bytes holding a block
 * state; NULL with a Python error set otherwise. */
void *fc_ext_state(Py_buffer *view, size_t size, const char *what);

/* Name of a status code, for error messages. */
const char *fc_ext_status_name(int status);

#endif /* FC_EXT_COMMON_H */
