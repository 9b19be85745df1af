/*
 * step_hash.c - silbridge.bridge._step.Blake2b, the trace hash as a Python object around
 * blake2b.c: update(buffer), digest(), hexdigest(), as hashlib's blake2b. It lives in this
 * extension so that Kernel.run_batch can feed the same state from C (step_batch.c) while
 * Python feeds it the steps it runs itself (bridge/bridge_loop.py). It keeps the GIL: the
 * loop's thread is its only user.
 */
#include "step_kernel.h"

#include "blake2b.h"

typedef struct {
    PyObject_HEAD
    sb_blake2b state;
} Blake2bObject;

static int Blake2b_init(Blake2bObject *self, PyObject *args, PyObject *kwds)
{
    static char *kwlist[] = {"digest_size", NULL};
    Py_ssize_t n = 16;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "|$n", kwlist, &n))
        return -1;
    if (sb_blake2b_init(&self->state, (size_t)n) < 0) {   /* a negative n wraps above 64 */
        PyErr_Format(PyExc_ValueError, "digest_size must be 1..%d", SB_BLAKE2B_MAX_DIGEST);
        return -1;
    }
    return 0;
}

static PyObject *Blake2b_update(Blake2bObject *self, PyObject *arg)
{
    Py_buffer v;
    if (PyObject_GetBuffer(arg, &v, PyBUF_C_CONTIGUOUS) < 0)
        return NULL;
    sb_blake2b_update(&self->state, v.buf, (size_t)v.len);
    PyBuffer_Release(&v);
    Py_RETURN_NONE;
}

static PyObject *Blake2b_digest(Blake2bObject *self, PyObject *Py_UNUSED(unused))
{
    uint8_t out[SB_BLAKE2B_MAX_DIGEST];
    sb_blake2b_digest(&self->state, out);
    return PyBytes_FromStringAndSize((const char *)out, (Py_ssize_t)self->state.digest_len);
}

static PyObject *Blake2b_hexdigest(Blake2bObject *self, PyObject *Py_UNUSED(unused))
{
    static const char HEX[] = "0123456789abcdef";
    uint8_t out[SB_BLAKE2B_MAX_DIGEST];
    char text[2 * SB_BLAKE2B_MAX_DIGEST];
    sb_blake2b_digest(&self->state, out);
    for (size_t i = 0; i < self->state.digest_len; i++) {
        text[2 * i] = HEX[out[i] >> 4];
        text[2 * i + 1] = HEX[out[i] & 15];
    }
    return PyUnicode_FromStringAndSize(text, (Py_ssize_t)(2 * self->state.digest_len));
}

static PyMethodDef Blake2b_methods[] = {
    {"update", (PyCFunction)Blake2b_update, METH_O, "update(buffer): hash its bytes next"},
    {"digest", (PyCFunction)Blake2b_digest, METH_NOARGS, "digest() -> bytes"},
    {"hexdigest", (PyCFunction)Blake2b_hexdigest, METH_NOARGS, "hexdigest() -> str"},
    {NULL, NULL, 0, NULL}};

PyTypeObject SbBlake2bType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "silbridge.bridge._step.Blake2b",
    .tp_doc = "Blake2b(*, digest_size=16): BLAKE2b (RFC 7693) as hashlib's blake2b gives "
              "it, which Kernel.run_batch can also feed from C",
    .tp_basicsize = sizeof(Blake2bObject),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)Blake2b_init,
    .tp_methods = Blake2b_methods,
};

sb_blake2b *sb_step_hash_state(PyObject *obj)
{
    if (!PyObject_TypeCheck(obj, &SbBlake2bType)) {
        PyErr_SetString(PyExc_TypeError, "trace_hash must be a _step.Blake2b");
        return NULL;
    }
    return &((Blake2bObject *)obj)->state;
}
