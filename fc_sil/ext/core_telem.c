/*
 * core_telem.c - Core methods that read what two ground-station messages carry: the
 * accelerometer vibration levels and clip counts (fc_vibe.h, VIBRATION) and the latest
 * report of each ESC (fc_esc.h, ESC_TELEMETRY_1_TO_4), and the latest BATTERY record (the
 * physics-side pack: SYS_STATUS, BATTERY_STATUS, the battery failsafe). Conversion only.
 */
#include "core_object.h"

/* vibration() -> (vibe_x, vibe_y, vibe_z [m/s^2], clip_count, samples) */
static PyObject *Core_vibration(CoreObject *self, PyObject *Py_UNUSED(unused))
{
    const fc_vibe_t *v = &self->core.vibe;
    float lv[3];
    fc_vibe_levels(v, lv);
    return Py_BuildValue("(dddkk)", (double)lv[0], (double)lv[1], (double)lv[2],
                         (unsigned long)v->clip_count, (unsigned long)v->samples);
}

/* esc_reports() -> (reports, rejected, motor_count, rows): rows one tuple per ESC slot
 * (sim_ns or -1, rpm, voltage_v, current_a, temperature_c, consumption_mah, count). */
static PyObject *Core_esc_reports(CoreObject *self, PyObject *Py_UNUSED(unused))
{
    const fc_esc_t *e = &self->core.esc;
    PyObject *rows = PyTuple_New(FC_ESC_MAX);
    if (rows == NULL)
        return NULL;
    for (int i = 0; i < FC_ESC_MAX; i++) {
        const fc_esc_report_t *r = &e->esc[i];
        PyObject *row = Py_BuildValue("(Ldddddk)", (long long)r->sim_ns, (double)r->rpm,
                                      (double)r->voltage_v, (double)r->current_a,
                                      (double)r->temperature_c, (double)r->consumption_mah,
                                      (unsigned long)r->count);
        if (row == NULL) {
            Py_DECREF(rows);
            return NULL;
        }
        PyTuple_SET_ITEM(rows, i, row);
    }
    return Py_BuildValue("(kkiN)", (unsigned long)e->reports, (unsigned long)e->rejected,
                         (int)e->motor_count, rows);
}

/* battery() -> (count, sim_ns or -1, voltage_v, current_a, consumed_mah, remaining,
 * temperature_c, lowest_cell_v, cell_count): the latest BATTERY record. */
static PyObject *Core_battery(CoreObject *self, PyObject *Py_UNUSED(unused))
{
    const sb_battery *b = &self->battery;
    return Py_BuildValue("(kLddddddi)", (unsigned long)self->battery_count,
                         (long long)(self->battery_count ? self->last_kind_ns[SB_KIND_BATTERY] : -1),
                         (double)b->voltage_v, (double)b->current_a, (double)b->consumed_mah,
                         (double)b->remaining, (double)b->temperature_c,
                         (double)b->lowest_cell_v, (int)b->cell_count);
}

PyMethodDef fc_ext_telem_methods[] = {
    {"vibration", (PyCFunction)Core_vibration, METH_NOARGS,
     "vibration() -> (vibe_x, vibe_y, vibe_z [m/s^2], clip_count, samples): ArduPilot's "
     "VIBRATION levels of the accel samples consumed so far (fc_vibe.h)."},
    {"esc_reports", (PyCFunction)Core_esc_reports, METH_NOARGS,
     "esc_reports() -> (reports, rejected, motor_count, rows): the latest telemetry of each "
     "ESC slot (fc_esc.h); a row is (sim_ns or -1, rpm, voltage_v, current_a, temperature_c, "
     "consumption_mah, count)."},
    {"battery", (PyCFunction)Core_battery, METH_NOARGS,
     "battery() -> (count, sim_ns or -1, voltage_v, current_a, consumed_mah, remaining, "
     "temperature_c, lowest_cell_v, cell_count): the latest BATTERY record (the bridge's pack)."},
    {NULL, NULL, 0, NULL},
};
