/*
 * core_log.c - log capture: the Core appends what it consumes and emits to bytearrays
 * the run's log owns (tools/logs/mcap_log.py cuts them into MCAP batches), so a run's log
 * costs a memcpy per record and no Python per record.
 *
 * bind_log(kind_queues, stage=, status=, log_pwm=, timing=) binds them: one queue per
 * record kind (a tuple indexed by the kind, None for kinds kept in the mixed stage),
 * the status rows, whether the PWM records the FC emits are logged (the FC logs them
 * when it runs in its own process), and the /timing rows poll_io writes (step_bound
 * has no clock). bind_log(None) turns capture off.
 */
#include "core_object.h"

#include <string.h>

/* Append len bytes to a bytearray (amortised growth); -1 with an exception on failure. */
int fc_ext_append_bytes(PyObject *ba, const void *src, Py_ssize_t len)
{
    if (len == 0)
        return 0;
    const Py_ssize_t old = PyByteArray_GET_SIZE(ba);
    if (PyByteArray_Resize(ba, old + len) < 0)
        return -1;
    memcpy(PyByteArray_AS_STRING(ba) + old, src, (size_t)len);
    return 0;
}

void fc_ext_clear_log(CoreObject *self)
{
    for (int i = 0; i < 16; i++)
        Py_CLEAR(self->log_kind[i]);
    Py_CLEAR(self->log_stage);
    Py_CLEAR(self->log_status);
    Py_CLEAR(self->log_timing);
    fc_ext_clear_fft_log(self);
    self->log_pwm = 0;
    self->log_on = 0;
}

static PyObject *Core_bind_log(CoreObject *self, PyObject *args, PyObject *kwds)
{
    static char *kwlist[] = {"kind_queues", "stage", "status", "log_pwm", "timing", NULL};
    PyObject *kinds, *stage = Py_None, *st = Py_None, *timing = Py_None;
    int log_pwm = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "O|$OOpO", kwlist, &kinds, &stage, &st,
                                     &log_pwm, &timing)) {
        return NULL;
    }
    if (kinds == Py_None) {
        fc_ext_clear_log(self);
        Py_RETURN_NONE;
    }
    if (!PyTuple_Check(kinds) || PyTuple_GET_SIZE(kinds) != 16) {
        PyErr_SetString(PyExc_TypeError, "bind_log: kind_queues must be a tuple of 16 "
                                         "(bytearray or None), one per record kind");
        return NULL;
    }
    PyObject *objs[19];
    for (int i = 0; i < 16; i++)
        objs[i] = PyTuple_GET_ITEM(kinds, i);
    objs[16] = stage;
    objs[17] = st;
    objs[18] = timing;
    for (int i = 0; i < 19; i++) {
        if (objs[i] != Py_None && !PyByteArray_Check(objs[i])) {
            PyErr_SetString(PyExc_TypeError, "bind_log: queues must be bytearrays or None");
            return NULL;
        }
    }
    fc_ext_clear_log(self);
    for (int i = 0; i < 16; i++)
        self->log_kind[i] = objs[i] == Py_None ? NULL : Py_NewRef(objs[i]);
    self->log_stage = stage == Py_None ? NULL : Py_NewRef(stage);
    self->log_status = st == Py_None ? NULL : Py_NewRef(st);
    self->log_timing = timing == Py_None ? NULL : Py_NewRef(timing);
    self->log_pwm = log_pwm;
    self->log_on = self->log_stage != NULL;
    for (int i = 0; i < 16; i++)
        self->log_on |= self->log_kind[i] != NULL;
    Py_RETURN_NONE;
}

/* Append whole records to their kind's queue (or the stage); -1 on failure. */
static int log_records(CoreObject *self, const unsigned char *base, Py_ssize_t n)
{
    for (Py_ssize_t i = 0; i < n; i++) {
        const unsigned char *rec = base + (size_t)i * SB_RECORD_SIZE;
        uint16_t kind;
        memcpy(&kind, rec, sizeof kind);
        PyObject *dest = self->log_kind[kind & 15u];
        if (dest == NULL)
            dest = self->log_stage;
        if (dest != NULL && fc_ext_append_bytes(dest, rec, SB_RECORD_SIZE) < 0)
            return -1;
    }
    return 0;
}

int fc_ext_log_batch(CoreObject *self, const unsigned char *recs, Py_ssize_t n,
                     const unsigned char *pwm, const fc_core_status_t *status, Py_ssize_t k)
{
    if (self->log_on &&
        (log_records(self, recs, n) < 0 || (self->log_pwm && log_records(self, pwm, k) < 0)))
        return -1;
    if (self->log_status != NULL &&
        fc_ext_append_bytes(self->log_status, status,
                            k * (Py_ssize_t)sizeof(fc_core_status_t)) < 0)
        return -1;
    return fc_ext_log_fft(self); /* FTN1/FTN2 at 10 Hz when bound and the FFT runs */
}

PyMethodDef fc_ext_log_methods[] = {
    {"bind_log", (PyCFunction)(void (*)(void))Core_bind_log, METH_VARARGS | METH_KEYWORDS,
     "bind_log(kind_queues[16], stage=, status=, log_pwm=, timing=): step_bound and poll_io "
     "append consumed records, PWM records (log_pwm) and status rows to these bytearrays, "
     "poll_io the /timing rows too; bind_log(None): off."},
    {NULL, NULL, 0, NULL},
};
