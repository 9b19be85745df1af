/*
 * blocksmodule.c - silbridge.fc_sil._blocks: each block of the C core on its own, for the
 * thin wrappers in silbridge.fc_sil.blocks and the tests (blocks_common.h says why it is
 * a module apart from _core).
 *
 * Each block's state lives in a caller-owned, 8-byte aligned buffer (a numpy uint64
 * array) of the size block_sizes() reports; the functions take that buffer first, then
 * the input arrays, then everything else by name: scalars as keywords and configuration
 * structs as dicts keyed by the C field names. Each runs its block over every row in C.
 */
#define FC_BLOCKS_IMPORT_ARRAY
#include "blocks_common.h"

#include "fc_alt_ctrl.h"
#include "fc_alt_est.h"
#include "fc_blend.h"
#include "fc_filter.h"
#include "fc_ins.h"
#include "fc_mahony.h"
#include "fc_mixer.h"
#include "fc_rate_pid.h"
#include "fc_shaper.h"
#include "fc_trim.h"

static PyObject *block_sizes(PyObject *m, PyObject *noargs)
{
    (void)m;
    (void)noargs;
    return Py_BuildValue("{s:n,s:n,s:n,s:n,s:n,s:n,s:n,s:n,s:n,s:n}", "shaper",
                         (Py_ssize_t)sizeof(fc_shaper_t), "filter",
                         (Py_ssize_t)sizeof(fc_filter_t), "ins", (Py_ssize_t)sizeof(fc_ins_t),
                         "mahony", (Py_ssize_t)sizeof(fc_mahony_t), "rate_pid",
                         (Py_ssize_t)sizeof(fc_rate_pid_t), "trim", (Py_ssize_t)sizeof(fc_trim_t),
                         "blend", (Py_ssize_t)sizeof(fc_blend_t), "mixer",
                         (Py_ssize_t)sizeof(fc_mixer_t), "alt_est",
                         (Py_ssize_t)sizeof(fc_alt_est_t), "alt_ctrl",
                         (Py_ssize_t)sizeof(fc_alt_ctrl_t));
}

static PyMethodDef module_methods[] = {
    {"block_sizes", block_sizes, METH_NOARGS, "sizeof of each block state."},
    {NULL, NULL, 0, NULL},
};

static PyMethodDef *const family_methods[] = {
    fc_blk_filter_methods, fc_blk_mahony_methods, fc_blk_attitude_methods,
    fc_blk_rate_methods,   fc_blk_mixer_methods,
};

static struct PyModuleDef moduledef = {
    PyModuleDef_HEAD_INIT, "_blocks",
    "The blocks of the silbridge flight-controller core, one by one (tests only).", -1,
    module_methods, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__blocks(void)
{
    import_array();
    PyObject *m = PyModule_Create(&moduledef);
    if (m == NULL) {
        return NULL;
    }
    for (size_t i = 0; i < sizeof family_methods / sizeof family_methods[0]; i++) {
        if (PyModule_AddFunctions(m, family_methods[i]) < 0) {
            Py_DECREF(m);
            return NULL;
        }
    }
    return m;
}
