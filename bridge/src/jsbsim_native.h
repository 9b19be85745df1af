/*
 * jsbsim_native.h - JSBSim's property nodes read and written from C, past the jsbsim
 * wheel's Python methods (issue 25: "read JSBSim's state through property-node handles").
 *
 * The wheel has no C API, but its extension exports JSBSim's C++ symbols, among them
 * SGPropertyNode::getDoubleValue() const and SGPropertyNode::setDoubleValue(double), and
 * each of its FGPropertyNode Python objects holds the C++ node's address. A node bound
 * here is the node its Python object wraps, proven before use: the address must point at
 * an object whose vtable is SGPropertyNode's (read without a fault, process_vm_readv),
 * and the C++ getter must return, bit for bit, what the Python method returns. Anything
 * else (another wheel, another layout, a symbol gone) leaves the node unbound, with the
 * reason, and the caller keeps the Python methods: the same values, only slower.
 *
 * What is saved: per node and step, the Python method's call, its argument check and the
 * float object of its result (docs/howto/speed.md, "How the step reaches JSBSim").
 */
#ifndef SB_JSBSIM_NATIVE_H
#define SB_JSBSIM_NATIVE_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <stdbool.h>

typedef double (*sb_jsb_get_fn)(const void *node);
typedef bool (*sb_jsb_set_fn)(void *node, double value);

typedef struct {
    sb_jsb_get_fn get;        /* SGPropertyNode::getDoubleValue() const */
    sb_jsb_set_fn set;        /* SGPropertyNode::setDoubleValue(double) */
    const void *vtable;       /* the address point of SGPropertyNode's vtable */
} sb_jsb_api;

/* The C++ node behind `method`, a bound get_double_value / set_double_value of a jsbsim
 * FGPropertyNode (method name given). On success returns the node and fills *api (the
 * same for every node of one wheel); else NULL, with the reason in why (no exception). */
void *sb_jsb_node(PyObject *method, const char *name, sb_jsb_api *api, char *why,
                  size_t why_len);

#endif /* SB_JSBSIM_NATIVE_H */
