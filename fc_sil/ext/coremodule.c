/*
 * coremodule.c - silbridge.fc_sil._core: the C flight-controller core driven from
 * Python. This file only assembles the module: the Core type, whose methods are the
 * tables of the files that implement them (core_object.h lists the files), the module
 * functions, and the status codes as constants. The per-block test bindings are
 * generated from the core's headers by the tests (tests/fc_sil/core_cffi.py), so a
 * flight carries none of them.
 */
#include "core_object.h"

/* The Core's method tables, in the order help(Core) lists them. */
static PyMethodDef *const method_tables[] = {
    fc_ext_object_methods, fc_ext_batch_methods, fc_ext_log_methods, fc_ext_poll_methods,
    fc_ext_step_methods,   fc_ext_sysid_methods, fc_ext_telem_methods, fc_ext_fft_methods,
};

/* Room for every method and the terminator; core_methods_join() refuses to overflow. */
#define CORE_METHODS_MAX 64
static PyMethodDef Core_methods[CORE_METHODS_MAX];

static int core_methods_join(void)
{
    size_t n = 0;
    for (size_t t = 0; t < sizeof method_tables / sizeof method_tables[0]; t++) {
        for (const PyMethodDef *m = method_tables[t]; m->ml_name != NULL; m++) {
            if (n + 1 >= CORE_METHODS_MAX) {
                PyErr_SetString(PyExc_SystemError, "_core: raise CORE_METHODS_MAX");
                return -1;
            }
            Core_methods[n++] = *m;
        }
    }
    Core_methods[n] = (PyMethodDef){NULL, NULL, 0, NULL};
    return 0;
}

static PyTypeObject CoreType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "silbridge.fc_sil._core.Core",
    .tp_basicsize = sizeof(CoreObject),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "The C flight-controller core (fc_core_t); see "
              "silbridge.fc_sil.flight_core.FlightCore.",
    .tp_new = fc_ext_core_new,
    .tp_dealloc = (destructor)fc_ext_core_dealloc,
    .tp_methods = Core_methods,
};

static struct PyModuleDef moduledef = {
    PyModuleDef_HEAD_INIT, "_core", "The silbridge flight-controller core (C).", -1,
    NULL, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__core(void)
{
    if (core_methods_join() < 0 || PyType_Ready(&CoreType) < 0) {
        return NULL;
    }
    PyObject *m = PyModule_Create(&moduledef);
    if (m == NULL) {
        return NULL;
    }
    if (PyModule_AddFunctions(m, fc_ext_layout_functions) < 0 ||
        PyModule_AddFunctions(m, fc_ext_bench_functions) < 0 ||
        PyModule_AddFunctions(m, fc_ext_fft_bench_functions) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    Py_INCREF(&CoreType);
    if (PyModule_AddObject(m, "Core", (PyObject *)&CoreType) < 0) {
        Py_DECREF(&CoreType);
        Py_DECREF(m);
        return NULL;
    }
    PyModule_AddIntConstant(m, "STATUS_SIZE", (long)sizeof(fc_core_status_t));
    PyModule_AddIntConstant(m, "FC_OK", FC_OK);
    PyModule_AddIntConstant(m, "FC_ERR_ARG", FC_ERR_ARG);
    PyModule_AddIntConstant(m, "FC_ERR_RANGE", FC_ERR_RANGE);
    PyModule_AddIntConstant(m, "FC_ERR_NONFINITE", FC_ERR_NONFINITE);
    PyModule_AddIntConstant(m, "FC_ERR_INDEX", FC_ERR_INDEX);
    PyModule_AddIntConstant(m, "FC_ERR_TYPE", FC_ERR_TYPE);
    return m;
}
