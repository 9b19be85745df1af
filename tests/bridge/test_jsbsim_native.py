"""JSBSim's property nodes read and written from C (bridge/src/jsbsim_native.h).

The step kernel calls SGPropertyNode's getter and setter in the jsbsim wheel's extension
directly, past the Python methods, once it has proven each node: the pointer inside the
Python object points at an SGPropertyNode (its vtable) and the C++ getter returns what the
Python method returns. The records must be the Python path's, bit for bit; anything the
kernel cannot prove keeps the Python methods and says why, never a guess.
"""

import pytest
from bridge_test_helpers import profile_digest

from silbridge.bridge import fdm as fdm_module
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator


def _fly(steps=4000, scenario="S1", **kw):
    sim = Simulator(load_scenario(scenario), **kw)
    return profile_digest(sim, steps), sim


def test_the_wheels_nodes_are_read_from_c():
    """The pinned jsbsim wheel is the one the proof was written for: a wheel that no longer
    passes it loses the fast path, and this says so before a benchmark does."""
    assert Simulator(load_scenario("S1")).jsbsim_nodes == "c"


@pytest.mark.parametrize("scenario", ["S1", "S3"])
def test_c_nodes_write_the_records_the_python_methods_write(scenario):
    c_hash, c_sim = _fly(scenario=scenario)
    py_hash, py_sim = _fly(scenario=scenario, jsbsim_native=False)
    assert (c_sim.jsbsim_nodes, py_sim.jsbsim_nodes) == ("c", "python: asked for")
    assert c_hash == py_hash
    assert c_sim.truth() == py_sim.truth()
    assert (c_sim.crashed, c_sim.crash_reason) == (py_sim.crashed, py_sim.crash_reason)


def test_the_c_setter_reaches_jsbsim():
    sim = Simulator(load_scenario("S1"))
    sim.step((1111.0, 1222.5, 1333.0, 1444.25))
    assert [h.get_double_value() for h in sim.fdm.h_pwm] == [1111.0, 1222.5, 1333.0, 1444.25]


def test_a_getter_that_is_not_a_node_keeps_every_call_on_python(monkeypatch):
    """One callable the kernel cannot prove (here a lambda) leaves all nodes on Python."""
    real = fdm_module.Fdm.sample_getters

    def wrapped(self):
        getters = real(self)
        inner = getters["p_rad_s"]
        getters["p_rad_s"] = lambda: inner()
        return getters
    monkeypatch.setattr(fdm_module.Fdm, "sample_getters", wrapped)
    py_hash, sim = _fly(steps=1500)
    assert sim.jsbsim_nodes == "python: getter p_rad_s: not a bound method"
    monkeypatch.undo()
    assert _fly(steps=1500)[0] == py_hash


def test_a_look_alike_node_is_refused(monkeypatch):
    """An object named FGPropertyNode that is not the wheel's (another layout) is never
    read as one: its memory holds no C++ node."""
    class FGPropertyNode:
        def __init__(self, node):
            self.node = node

        def get_double_value(self):
            return self.node.get_double_value()

    real = fdm_module.Fdm.sample_getters

    def look_alike(self):
        getters = real(self)
        getters["q_rad_s"] = FGPropertyNode(self.sample_nodes["q_rad_s"]).get_double_value
        return getters
    monkeypatch.setattr(fdm_module.Fdm, "sample_getters", look_alike)
    sim = Simulator(load_scenario("S1"))
    assert sim.jsbsim_nodes.startswith("python: getter q_rad_s: FGPropertyNode objects of ")
    assert sim.jsbsim_nodes.endswith("bytes: not the known layout")


def test_an_uninitialised_node_is_refused(monkeypatch):
    import jsbsim
    real = fdm_module.Fdm.sample_getters

    def empty(self):
        getters = real(self)
        getters["r_rad_s"] = jsbsim.FGPropertyNode().get_double_value
        return getters
    monkeypatch.setattr(fdm_module.Fdm, "sample_getters", empty)
    sim = Simulator(load_scenario("S1"))
    assert sim.jsbsim_nodes == "python: getter r_rad_s: an uninitialised FGPropertyNode"


@pytest.mark.parametrize("target", ["unmapped", "not a node"])
def test_a_pointer_that_is_not_a_node_is_refused_without_a_crash(monkeypatch, target):
    """The address inside the wheel's object is checked before it is used: an address where
    nothing is mapped, or memory that is not an SGPropertyNode, is refused (a wrong layout
    would give either). The real address is put back before anything else can use it."""
    import ctypes
    stand_in = ctypes.create_string_buffer(64)       # zeros: no SGPropertyNode vtable
    address = 0x1000 if target == "unmapped" else ctypes.addressof(stand_in)
    real_bind = Simulator._bind_native

    def bind_with_a_wrong_pointer(self, wanted):
        node = self.fdm.sample_nodes["p_rad_s"]
        field = ctypes.c_void_p.from_address(id(node) + type(node).__basicsize__ - 8)
        kept = field.value
        field.value = address
        try:
            return real_bind(self, wanted)
        finally:
            field.value = kept
    monkeypatch.setattr(Simulator, "_bind_native", bind_with_a_wrong_pointer)
    sim = Simulator(load_scenario("S1"))
    assert sim.jsbsim_nodes == ("python: getter p_rad_s: the FGPropertyNode's pointer is not "
                                "an SGPropertyNode")
    sim.step((1000.0,) * 4)                           # the Python methods fly on
