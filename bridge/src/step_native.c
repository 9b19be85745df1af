/*
 * step_native.c - Kernel.bind_native(): the step reads the FDM sample and writes the pulse
 * widths through JSBSim's C++ nodes (jsbsim_native.h) instead of their Python methods.
 * All or none: one node that cannot be proven keeps every call on the Python methods,
 * and the reason is returned for the caller to say.
 */
#include "step_kernel.h"

/* bind_native() -> None when bound, else a str: why the Python methods stay. */
PyObject *Kernel_bind_native(Kernel *self, PyObject *Py_UNUSED(unused))
{
    if (self->stage.state == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "Kernel is not initialised");
        return NULL;
    }
    char why[224];
    sb_jsb_api api;
    void *get[SB_FDM_SAMPLE_FIELD_COUNT], *set[4];
    for (int i = 0; i < SB_FDM_SAMPLE_FIELD_COUNT; i++) {
        get[i] = sb_jsb_node(self->getters[i].obj, "get_double_value", &api, why, sizeof why);
        if (get[i] == NULL)
            return PyUnicode_FromFormat("getter %s: %s", SB_FDM_SAMPLE_FIELDS[i].name, why);
    }
    for (int i = 0; i < 4; i++) {
        set[i] = sb_jsb_node(self->setters[i].obj, "set_double_value", &api, why, sizeof why);
        if (set[i] == NULL)
            return PyUnicode_FromFormat("PWM setter %d: %s", i + 1, why);
    }
    /* Each Python node wraps its own C++ node: two getters on one node would mean the
     * pointer was read from the wrong place. */
    void *all[SB_FDM_SAMPLE_FIELD_COUNT + 4];
    memcpy(all, get, sizeof get);
    memcpy(all + SB_FDM_SAMPLE_FIELD_COUNT, set, sizeof set);
    for (int i = 0; i < SB_FDM_SAMPLE_FIELD_COUNT + 4; i++)
        for (int j = 0; j < i; j++)
            if (all[i] == all[j])
                return PyUnicode_FromString("two properties read from one C++ node");
    memcpy(self->get_node, get, sizeof get);
    memcpy(self->set_node, set, sizeof set);
    self->jsb = api;
    Py_RETURN_NONE;
}
