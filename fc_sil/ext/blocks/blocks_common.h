/*
 * blocks_common.h - what the files of silbridge.fc_sil._blocks share: the numpy set-up,
 * the check of a caller-owned state buffer, array conversion, and a configuration struct
 * read from a dict by field name (a flat {name, kind, offsetof} table per struct, the
 * shape Betaflight gives its settings table).
 *
 * _blocks is a test-only module: it binds each block of the C core on its own, for
 * silbridge.fc_sil.blocks and the tests (as Crazyflie's bindings do); a flight never
 * imports it. Each family file (filters, estimation, attitude, rate control, mixer)
 * exports its NULL-terminated method table; blocksmodule.c adds them all.
 */
#ifndef FC_BLOCKS_COMMON_H
#define FC_BLOCKS_COMMON_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#define PY_ARRAY_UNIQUE_SYMBOL silbridge_fc_blocks_ARRAY_API
#ifndef FC_BLOCKS_IMPORT_ARRAY
#define NO_IMPORT_ARRAY
#endif
#include <numpy/arrayobject.h>

#include <stddef.h>

/* A writable, 8-byte aligned buffer of at least `size` bytes holding a block state;
 * NULL with a Python error set otherwise. */
void *fc_blk_state(Py_buffer *view, size_t size, const char *what);

/* The end of a call that returns nothing: release the state buffer, then None when ok,
 * else NULL (the error is already set). */
PyObject *fc_blk_release_none(Py_buffer *view, int ok);

/* A C-contiguous float32 array of shape (n,) (cols 0) or (n, cols); NULL + error otherwise. */
PyArrayObject *fc_blk_f32_in(PyObject *obj, int cols, const char *what);
/* A C-contiguous 1-D uint8 array of flags; NULL + error otherwise. */
PyArrayObject *fc_blk_u8_in(PyObject *obj, const char *what);
/* A new float32 array of shape (n,) (cols 0) or (n, cols). */
PyObject *fc_blk_f32_out(npy_intp n, int cols);
/* 1 when a has n rows; 0 with a ValueError otherwise. */
int fc_blk_same_len(npy_intp n, PyArrayObject *a);

/* One field of a configuration struct, read from the dict entry of the same name. */
typedef enum { FC_BLK_F32, FC_BLK_BOOL, FC_BLK_F32X3 } fc_blk_kind_t;
typedef struct {
    const char *name;
    fc_blk_kind_t kind;
    size_t offset;  /* offsetof in the struct */
    int optional;   /* 1: may be missing (stays 0) */
} fc_blk_field_t;

#define FC_BLK_FIELD(type, field, kind) {#field, kind, offsetof(type, field), 0}
#define FC_BLK_OPTIONAL(type, field, kind) {#field, kind, offsetof(type, field), 1}

/* Zero cfg (size bytes), then fill it from the dict `obj`: every required field must be
 * there and no other key. 1 on success, 0 with a TypeError/KeyError naming the field. */
int fc_blk_config(PyObject *obj, const fc_blk_field_t *fields, size_t n_fields, void *cfg,
                  size_t size, const char *what);
#define FC_BLK_CONFIG(obj, fields, cfg, what)                                              \
    fc_blk_config((obj), (fields), sizeof(fields) / sizeof((fields)[0]), (cfg), sizeof *(cfg), \
                  (what))

/* A method table entry's function and flags for a function taking keywords. */
#define FC_BLK_KW(f) (PyCFunction)(void (*)(void))(f), METH_VARARGS | METH_KEYWORDS

/* The families' method tables (blocksmodule.c adds them to the module). */
extern PyMethodDef fc_blk_filter_methods[];
extern PyMethodDef fc_blk_mahony_methods[];
extern PyMethodDef fc_blk_attitude_methods[];
extern PyMethodDef fc_blk_rate_methods[];
extern PyMethodDef fc_blk_mixer_methods[];

#endif /* FC_BLOCKS_COMMON_H */
