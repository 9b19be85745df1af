/*
 * blocks_common.c - the helpers every block binding uses (blocks_common.h): state buffer
 * check, array conversion, and configuration structs read from dicts by field name, so a
 * test names each gain it sets and a reordered struct cannot shift values silently.
 */
#include "blocks_common.h"

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

void *fc_blk_state(Py_buffer *view, size_t size, const char *what)
{
    if (view->readonly || (size_t)view->len < size || ((uintptr_t)view->buf & 7u) != 0) {
        PyErr_Format(PyExc_ValueError,
                     "%s state needs a writable 8-byte aligned buffer of %zu bytes "
                     "(use the wrapper classes in silbridge.fc_sil.blocks)",
                     what, size);
        return NULL;
    }
    return view->buf;
}

PyObject *fc_blk_release_none(Py_buffer *view, int ok)
{
    PyBuffer_Release(view);
    if (!ok) {
        return NULL;
    }
    Py_RETURN_NONE;
}

PyArrayObject *fc_blk_f32_in(PyObject *obj, int cols, const char *what)
{
    PyArrayObject *a = (PyArrayObject *)PyArray_FROMANY(obj, NPY_FLOAT32, 1, 2,
                                                        NPY_ARRAY_IN_ARRAY | NPY_ARRAY_FORCECAST);
    if (a == NULL) {
        return NULL;
    }
    const int ok = (cols == 0) ? PyArray_NDIM(a) == 1
                               : (PyArray_NDIM(a) == 2 && PyArray_DIM(a, 1) == cols);
    if (!ok) {
        PyErr_Format(PyExc_ValueError, "%s must have shape (n,%s)", what, cols ? " 3/4" : "");
        Py_DECREF(a);
        return NULL;
    }
    return a;
}

PyArrayObject *fc_blk_u8_in(PyObject *obj, const char *what)
{
    PyArrayObject *a = (PyArrayObject *)PyArray_FROMANY(obj, NPY_UINT8, 1, 1,
                                                        NPY_ARRAY_IN_ARRAY | NPY_ARRAY_FORCECAST);
    if (a == NULL) {
        PyErr_Format(PyExc_ValueError, "%s must be a 1-D array of flags", what);
    }
    return a;
}

PyObject *fc_blk_f32_out(npy_intp n, int cols)
{
    npy_intp dims[2] = {n, cols};
    return PyArray_SimpleNew(cols ? 2 : 1, dims, NPY_FLOAT32);
}

int fc_blk_same_len(npy_intp n, PyArrayObject *a)
{
    if (PyArray_DIM(a, 0) != n) {
        PyErr_SetString(PyExc_ValueError, "input arrays must have the same length");
        return 0;
    }
    return 1;
}

/* ---- configuration by field name ---------------------------------------------- */

/* One float as PyArg_Parse's "f" reads it (any object with __float__ or __index__). */
static int read_f32(PyObject *v, float *out)
{
    const double d = PyFloat_AsDouble(v);
    if (d == -1.0 && PyErr_Occurred()) {
        return 0;
    }
    *out = (float)d;
    return 1;
}

static int read_field(PyObject *v, const fc_blk_field_t *f, unsigned char *base,
                      const char *what)
{
    switch (f->kind) {
    case FC_BLK_F32:
        return read_f32(v, (float *)(base + f->offset));
    case FC_BLK_BOOL: {
        const int b = PyObject_IsTrue(v);
        if (b < 0) {
            return 0;
        }
        *(bool *)(base + f->offset) = b != 0;
        return 1;
    }
    case FC_BLK_F32X3: {
        PyObject *seq = PySequence_Fast(v, "");
        if (seq == NULL || PySequence_Fast_GET_SIZE(seq) != 3) {
            Py_XDECREF(seq);
            PyErr_Format(PyExc_TypeError, "%s config: %s must be 3 numbers", what, f->name);
            return 0;
        }
        float *dst = (float *)(base + f->offset);
        int ok = 1;
        for (Py_ssize_t i = 0; i < 3 && ok; i++) {
            ok = read_f32(PySequence_Fast_GET_ITEM(seq, i), &dst[i]);
        }
        Py_DECREF(seq);
        return ok;
    }
    }
    PyErr_Format(PyExc_SystemError, "%s config: field %s has no kind", what, f->name);
    return 0;
}

/* The first key of d that names no field (for the error message); NULL if none. */
static PyObject *unknown_key(PyObject *d, const fc_blk_field_t *fields, size_t n_fields)
{
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    while (PyDict_Next(d, &pos, &key, &value)) {
        const char *k = PyUnicode_Check(key) ? PyUnicode_AsUTF8(key) : NULL;
        size_t i = 0;
        while (k != NULL && i < n_fields && strcmp(k, fields[i].name) != 0) {
            i++;
        }
        if (k == NULL || i == n_fields) {
            return key;
        }
    }
    return NULL;
}

int fc_blk_config(PyObject *obj, const fc_blk_field_t *fields, size_t n_fields, void *cfg,
                  size_t size, const char *what)
{
    if (!PyDict_Check(obj)) {
        PyErr_Format(PyExc_TypeError, "%s config must be a dict of named fields", what);
        return 0;
    }
    memset(cfg, 0, size);
    Py_ssize_t found = 0;
    for (size_t i = 0; i < n_fields; i++) {
        PyObject *v = PyDict_GetItemString(obj, fields[i].name);
        if (v == NULL) {
            if (fields[i].optional) {
                continue;
            }
            PyErr_Format(PyExc_KeyError, "%s config: missing field '%s'", what, fields[i].name);
            return 0;
        }
        if (!read_field(v, &fields[i], cfg, what)) {
            return 0;
        }
        found++;
    }
    if (found != PyDict_Size(obj)) {
        PyObject *key = unknown_key(obj, fields, n_fields);
        PyErr_Format(PyExc_KeyError, "%s config: unknown field %R", what,
                     key != NULL ? key : Py_None);
        return 0;
    }
    return 1;
}
