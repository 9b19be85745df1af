/*
 * jsbsim_native.c - a jsbsim FGPropertyNode Python object's C++ node, proven before use
 * (jsbsim_native.h says what and why).
 */
#include "jsbsim_native.h"

#include <dlfcn.h>
#include <errno.h>
#include <stdint.h>
#include <string.h>
#include <sys/uio.h>
#include <unistd.h>

/* The wheel's symbols, resolved once per process (all nodes come from one extension). */
static struct {
    int state;                /* 0 not tried, 1 resolved, -1 failed (reason below) */
    sb_jsb_api api;
    char why[160];
} g_wheel;

/* The wheel's three symbols, found in the shared object that holds `code` (its node
 * type's code: whatever the extension is called, wherever it is installed). */
static int resolve(void *code)
{
    if (g_wheel.state != 0)
        return g_wheel.state;
    g_wheel.state = -1;
    Dl_info info;
    if (dladdr(code, &info) == 0 || info.dli_fname == NULL) {
        snprintf(g_wheel.why, sizeof g_wheel.why, "the jsbsim extension was not found");
        return -1;
    }
    void *lib = dlopen(info.dli_fname, RTLD_NOLOAD | RTLD_LAZY);
    if (lib == NULL) {
        snprintf(g_wheel.why, sizeof g_wheel.why, "dlopen: %s", dlerror());
        return -1;
    }
    /* Itanium C++ names: SGPropertyNode::getDoubleValue() const, ::setDoubleValue(double),
     * and the vtable, whose address point is two pointers in (offset to top, type info). */
    void *get = dlsym(lib, "_ZNK14SGPropertyNode14getDoubleValueEv");
    void *set = dlsym(lib, "_ZN14SGPropertyNode14setDoubleValueEd");
    void *vtab = dlsym(lib, "_ZTV14SGPropertyNode");
    dlclose(lib);             /* Python keeps the extension loaded: the addresses stay */
    if (get == NULL || set == NULL || vtab == NULL) {
        snprintf(g_wheel.why, sizeof g_wheel.why,
                 "the jsbsim extension does not export SGPropertyNode's getter, setter "
                 "and vtable");
        return -1;
    }
    g_wheel.api.get = (sb_jsb_get_fn)get;
    g_wheel.api.set = (sb_jsb_set_fn)set;
    g_wheel.api.vtable = (const char *)vtab + 2 * sizeof(void *);
    g_wheel.state = 1;
    return 1;
}

/* *out = the pointer-sized word at addr, read without faulting; 0 on success, else errno
 * (EFAULT: nothing mapped there; EPERM or ENOSYS: a sandbox that forbids the call). */
static int read_word(const void *addr, const void **out)
{
    struct iovec local = {.iov_base = (void *)out, .iov_len = sizeof *out};
    struct iovec remote = {.iov_base = (void *)addr, .iov_len = sizeof *out};
    errno = 0;
    if (process_vm_readv(getpid(), &local, 1, &remote, 1, 0) == (ssize_t)sizeof *out)
        return 0;
    return errno ? errno : EIO;
}

/* The node pointer inside a jsbsim FGPropertyNode object: the Cython struct is the object
 * head, its methods' table, then the SGSharedPtr (one pointer). Any other shape: NULL. */
static void *node_field(PyObject *obj, char *why, size_t why_len)
{
    PyTypeObject *t = Py_TYPE(obj);
    const char *dot = strrchr(t->tp_name, '.');
    const char *name = dot ? dot + 1 : t->tp_name;
    if (strcmp(name, "FGPropertyNode") != 0) {
        snprintf(why, why_len, "bound to a %s, not a jsbsim FGPropertyNode", t->tp_name);
        return NULL;
    }
    if (t->tp_basicsize != (Py_ssize_t)(sizeof(PyObject) + 2 * sizeof(void *)) ||
        t->tp_dictoffset != 0 || t->tp_weaklistoffset != 0 || t->tp_itemsize != 0) {
        snprintf(why, why_len, "FGPropertyNode objects of %zd bytes: not the known layout",
                 t->tp_basicsize);
        return NULL;
    }
    void *node;
    memcpy(&node, (char *)obj + sizeof(PyObject) + sizeof(void *), sizeof node);
    if (node == NULL)
        snprintf(why, why_len, "an uninitialised FGPropertyNode");
    return node;
}

void *sb_jsb_node(PyObject *method, const char *name, sb_jsb_api *api, char *why,
                  size_t why_len)
{
    if (!PyMethod_Check(method)) {
        snprintf(why, why_len, "not a bound method");
        return NULL;
    }
    PyObject *fname = PyObject_GetAttrString(PyMethod_GET_FUNCTION(method), "__name__");
    const int same = fname != NULL && PyUnicode_Check(fname) &&
                     PyUnicode_CompareWithASCIIString(fname, name) == 0;
    Py_XDECREF(fname);
    PyErr_Clear();
    if (!same) {
        snprintf(why, why_len, "not a bound %s", name);
        return NULL;
    }
    PyObject *obj = PyMethod_GET_SELF(method);
    void *node = node_field(obj, why, why_len);
    if (node == NULL)
        return NULL;
    if (resolve((void *)Py_TYPE(obj)->tp_dealloc) < 0) {
        snprintf(why, why_len, "%s", g_wheel.why);
        return NULL;
    }
    const void *vptr;
    const int err = read_word(node, &vptr);
    if (err != 0 && err != EFAULT) {
        snprintf(why, why_len, "its node could not be checked (process_vm_readv: %s)",
                 strerror(err));
        return NULL;
    }
    if (err == EFAULT || vptr != g_wheel.api.vtable) {
        snprintf(why, why_len, "the FGPropertyNode's pointer is not an SGPropertyNode");
        return NULL;
    }
    /* The last proof: the C++ getter and the Python method agree, bit for bit. */
    PyObject *r = PyObject_CallMethod(obj, "get_double_value", NULL);
    const double py = r != NULL ? PyFloat_AsDouble(r) : -1.0;
    Py_XDECREF(r);
    if (PyErr_Occurred()) {
        PyErr_Clear();
        snprintf(why, why_len, "its Python get_double_value failed");
        return NULL;
    }
    const double c = g_wheel.api.get(node);
    if (memcmp(&py, &c, sizeof c) != 0) {
        snprintf(why, why_len, "the C++ getter read %.17g where Python read %.17g", c, py);
        return NULL;
    }
    *api = g_wheel.api;
    return node;
}
