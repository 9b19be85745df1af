/*
 * step_call.h - a Python callable the step calls from C many times a step (JSBSim's bound
 * getters, setters and run, the FC's poll), called through its vectorcall entry (PEP 590)
 * without the generic call's layers.
 *
 * A bound method (the jsbsim wheel's are `method` objects around Cython functions) is split
 * once into its function and its self; each call then goes straight to the function's
 * vectorcall with self as the first argument, which is what the interpreter's own method
 * call does (classobject.c method_vectorcall). PyObject_CallNoArgs on the bound method
 * costs about 80 instructions more per call (the method layer, the generic dispatch, the
 * result check), and a step makes 27 such calls (docs/howto/speed.md). Anything without a
 * vectorcall entry is called the generic way. Only public C API: PyMethod_*,
 * PyVectorcall_Function.
 */
#ifndef SB_STEP_CALL_H
#define SB_STEP_CALL_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

typedef struct {
    PyObject *obj;        /* the callable as given (a strong reference: it owns the two below) */
    vectorcallfunc vf;    /* NULL: call obj the generic way */
    PyObject *func;       /* borrowed from obj: the function behind a bound method, or obj */
    PyObject *self;       /* borrowed from obj: the bound self, or NULL */
} sb_call;

/* Split obj (a strong reference is taken; the previous one dropped) into its call path. */
static inline void sb_call_set(sb_call *c, PyObject *obj)
{
    Py_XINCREF(obj);
    Py_XSETREF(c->obj, obj);
    c->vf = NULL;
    c->func = obj;
    c->self = NULL;
    if (obj == NULL)
        return;
    if (PyMethod_Check(obj)) {
        c->func = PyMethod_GET_FUNCTION(obj);
        c->self = PyMethod_GET_SELF(obj);
    }
    c->vf = PyVectorcall_Function(c->func);
}

static inline void sb_call_clear(sb_call *c)
{
    Py_CLEAR(c->obj);
    c->vf = NULL;
    c->func = c->self = NULL;
}

/* c() -> new reference, or NULL with the exception set. */
static inline PyObject *sb_call0(const sb_call *c)
{
    if (c->vf == NULL)
        return PyObject_CallNoArgs(c->obj);
    if (c->self == NULL)
        return c->vf(c->func, NULL, 0, NULL);
    PyObject *args[1] = {c->self};
    return c->vf(c->func, args, 1, NULL);
}

/* c(arg) -> new reference, or NULL with the exception set. */
static inline PyObject *sb_call1(const sb_call *c, PyObject *arg)
{
    if (c->vf == NULL)
        return PyObject_CallOneArg(c->obj, arg);
    if (c->self == NULL)
        return c->vf(c->func, &arg, 1, NULL);
    PyObject *args[2] = {c->self, arg};
    return c->vf(c->func, args, 2, NULL);
}

/* A float result as a double (the getters return exact floats: no method lookup). */
static inline double sb_call_double(PyObject *r)
{
    return PyFloat_CheckExact(r) ? PyFloat_AS_DOUBLE(r) : PyFloat_AsDouble(r);
}

#endif /* SB_STEP_CALL_H */
