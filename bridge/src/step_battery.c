/*
 * step_battery.c - the Kernel methods of the physics-side battery (battery.h): Python
 * configures the pack (bridge/battery/), the fault engine switches a weak cell or a
 * capacity loss through it, and readers (the mag's motor interference, the ESC telemetry,
 * the run summary) read its state here. The step itself runs the pack: step_run.c reads
 * the motors' torque through the getters given here on a report's step, the sensor stage
 * writes the record (sensor_stage.c), or write_battery does when Python finishes the step.
 */
#include "step_kernel.h"

/* The four motors' shaft torque now [lbf ft]; 0, or -1 with the getter's exception. */
static int read_torque(Kernel *self, double torque[4])
{
    for (int i = 0; i < 4; i++) {
        PyObject *r = sb_call0(&self->pack_torque[i]);
        if (r == NULL)
            return -1;
        torque[i] = sb_call_double(r);
        Py_DECREF(r);
        if (torque[i] == -1.0 && PyErr_Occurred())
            return -1;
    }
    return 0;
}

/* The ESCs' total input power after this step into pack.esc_w; 0, or -1 with an
 * exception. Summed left to right from 0.0, as the reference's sum() does. */
int sb_step_pack_load(Kernel *self, const double omega_rad_s[4])
{
    double torque[4], p[4];
    if (read_torque(self, torque) < 0)
        return -1;
    sb_pack *b = &self->stage.pack;
    sb_pack_esc_power(b, omega_rad_s, torque, p);
    double sum = 0.0;
    for (int i = 0; i < 4; i++)
        sum += p[i];
    b->esc_w = sum;
    return 0;
}

static int need_pack(Kernel *self)
{
    if (self->stage.pack.on)
        return 0;
    PyErr_SetString(PyExc_RuntimeError, "the battery is not configured: configure_battery()");
    return -1;
}

/* configure_battery(torque, cells, capacity_mah, internal_mohm, avionics_a, initial_soc,
 * temperature_c, air_c, activation_kj_mol, heat_capacity_j_k, thermal_k_per_w, rate_hz,
 * ke_v_s_rad, winding_ohm): a fresh pack (sb_pack_cfg names the keys and units). */
PyObject *Kernel_configure_battery(Kernel *self, PyObject *args, PyObject *kwds)
{
    static char *kwlist[] = {"torque", "cells", "capacity_mah", "internal_mohm", "avionics_a",
                             "initial_soc", "temperature_c", "air_c", "activation_kj_mol",
                             "heat_capacity_j_k", "thermal_k_per_w", "rate_hz", "ke_v_s_rad",
                             "winding_ohm", NULL};
    PyObject *torque;
    sb_pack_cfg c;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "$Oidddddddddddd", kwlist, &torque, &c.cells,
                                     &c.capacity_mah, &c.internal_mohm, &c.avionics_a,
                                     &c.initial_soc, &c.temperature_c, &c.air_c,
                                     &c.activation_kj_mol, &c.heat_capacity_j_k,
                                     &c.thermal_k_per_w, &c.rate_hz, &c.ke_v_s_rad,
                                     &c.winding_ohm))
        return NULL;
    PyObject *get[4] = {NULL, NULL, NULL, NULL};
    if (sb_step_take_callables(torque, get, 4, "torque") < 0) {
        for (int i = 0; i < 4; i++)
            Py_XDECREF(get[i]);
        return NULL;
    }
    for (int i = 0; i < 4; i++) {
        sb_call_set(&self->pack_torque[i], get[i]);
        Py_DECREF(get[i]);
    }
    if (sb_pack_init(&self->stage.pack, &c) < 0) {
        PyErr_Format(PyExc_ValueError, "configure_battery: 1..%d cells, and capacity_mah, "
                     "rate_hz, ke_v_s_rad > 0", SB_PACK_MAX_CELLS);
        return NULL;
    }
    Py_RETURN_NONE;
}

/* write_battery(slot) -> 0 or 1: on a step Python finishes (F_SLOW_DUE), the report due
 * at this step, written at slot (after Python's GNSS and setpoint records). */
PyObject *Kernel_write_battery(Kernel *self, PyObject *arg)
{
    const Py_ssize_t slot = PyLong_AsSsize_t(arg);
    if ((slot == -1 && PyErr_Occurred()) || need_pack(self) < 0)
        return NULL;
    const int64_t sim_ns = self->step_index * self->dt_ns;
    if (!sb_pack_due(&self->stage.pack, sim_ns))
        return PyLong_FromLong(0);
    if (slot < 0 || slot >= self->n_slots) {
        PyErr_Format(PyExc_ValueError, "slot %zd outside the step buffer", slot);
        return NULL;
    }
    const double *st = self->stage.state;   /* the rotor speeds the step left */
    if (sb_step_pack_load(self, &st[ST_OMEGA]) < 0)
        return NULL;
    sb_pack_report(&self->stage.pack, &self->slots[slot], sim_ns);
    return PyLong_FromLong(1);
}

PyObject *Kernel_battery_state(Kernel *self, PyObject *unused)
{
    (void)unused;
    if (need_pack(self) < 0)
        return NULL;
    const sb_pack *b = &self->stage.pack;
    double low = b->cell_v[0];
    for (int k = 1; k < b->c.cells; k++)
        low = b->cell_v[k] < low ? b->cell_v[k] : low;
    return Py_BuildValue("(ddddddkL)", b->voltage_v, b->current_a, b->consumed_mah,
                         sb_pack_remaining(b), b->temp_c, low, (unsigned long)b->seq,
                         (long long)b->next_ns);
}

PyObject *Kernel_battery_solve(Kernel *self, PyObject *arg)
{
    const double esc_w = PyFloat_AsDouble(arg);
    if ((esc_w == -1.0 && PyErr_Occurred()) || need_pack(self) < 0)
        return NULL;
    sb_pack_solution s;
    sb_pack_solve(&self->stage.pack, esc_w, &s);
    return Py_BuildValue("(dd)", s.voltage_v, s.current_a);
}

PyObject *Kernel_battery_esc_power(Kernel *self, PyObject *omega)
{
    double w[4], torque[4], p[4];
    if (need_pack(self) < 0 || !PyArg_ParseTuple(omega, "dddd", &w[0], &w[1], &w[2], &w[3]))
        return NULL;
    if (read_torque(self, torque) < 0)
        return NULL;
    sb_pack_esc_power(&self->stage.pack, w, torque, p);
    return Py_BuildValue("(dddd)", p[0], p[1], p[2], p[3]);
}

PyObject *Kernel_set_battery_cell(Kernel *self, PyObject *args)
{
    int cell;
    double offset_v, r_scale;
    if (!PyArg_ParseTuple(args, "idd", &cell, &offset_v, &r_scale) || need_pack(self) < 0)
        return NULL;
    if (sb_pack_set_cell(&self->stage.pack, cell, offset_v, r_scale) < 0) {
        PyErr_Format(PyExc_ValueError, "set_battery_cell: cell %d outside the pack's %d", cell,
                     self->stage.pack.c.cells);
        return NULL;
    }
    Py_RETURN_NONE;
}

PyObject *Kernel_battery_lose_charge(Kernel *self, PyObject *arg)
{
    const double fraction = PyFloat_AsDouble(arg);
    if ((fraction == -1.0 && PyErr_Occurred()) || need_pack(self) < 0)
        return NULL;
    sb_pack_lose_charge(&self->stage.pack, fraction);
    Py_RETURN_NONE;
}
