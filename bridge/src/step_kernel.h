/*
 * step_kernel.h - the Kernel object of silbridge.bridge._step, the CPython shim around
 * the pure-C sensor stage (sensor_stage.h), shared by stepmodule.c (the Python type:
 * construction, arguments, the module), step_run.c (the step: drive JSBSim, fill the
 * FDM sample, call the stage) and step_config.c (the methods that configure it between
 * steps: noise blocks, sensors, forces). Only these files know Python and JSBSim.
 */
#ifndef SB_STEP_KERNEL_H
#define SB_STEP_KERNEL_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <math.h>
#include <string.h>

#include "blake2b.h"
#include "jsbsim_native.h"
#include "sb_records.h"
#include "sensor_stage.h"
#include "step_call.h"
#include "step_lockstep.h"

/* A disturbance force (disturbances.py): f = c * sin(w (t - t_on) + phase), or c. */
typedef struct {
    double c_n, w_rad_s, t_on_s, phase_rad, axis[3];
    int periodic;
} force_item_t;

/* The summed forces of one frame go into the direction of its 1 N external force. */
typedef struct {
    PyObject *set[3];         /* bound set_double_value of the direction x, y, z */
    force_item_t *items;
    Py_ssize_t n;
} force_frame_t;

/* The in-process lockstep batch (step_batch.c): the objects and buffer views behind the
 * plain-C lockstep state (step_lockstep.h) that Kernel.run_batch steps. */
typedef struct {
    sb_lockstep ls;           /* the pointers into the views below, for the plain-C side */
    PyObject *capsule;        /* the bridge's segment capsule: keeps the segment alive */
    sb_call fc_poll;          /* bound Core.poll_io of the in-process FC (obj NULL: none) */
    PyObject *pwm_obj[4];     /* the held pulse widths as floats, for the setters */
    int64_t pwm_held[4];      /* their values [us]: rebuilt only when they change */
    Py_buffer trace;          /* uint8: step records then PWM records, the hash's order */
    Py_buffer pwm;            /* 64-byte records: where the PWM is popped */
    Py_buffer io;             /* int64[SB_IO_WORDS] */
    Py_buffer rotor;          /* float64 (rows, 4): rotor speeds after each step, or none */
    Py_buffer errors;         /* float64[SB_ERR_COUNT] */
    PyObject *hash_obj;       /* the trace hash's _step.Blake2b the batch feeds, or NULL */
    sb_blake2b *hash;         /*   its state */
    size_t hashed;            /*   trace bytes of this batch hashed so far */
} sb_batch;

typedef struct {
    PyObject_HEAD
    sb_call setters[4];       /* bound set_double_value of fcs/m1..4-pwm-us */
    sb_call run;              /* bound FGFDMExec.run */
    /* The FDM sample's getters, in SB_FDM_SAMPLE_FIELDS order (bound by name at init),
     * called from C (docs/howto/speed.md: how the step reaches JSBSim, and why so). */
    sb_call getters[SB_FDM_SAMPLE_FIELD_COUNT];
    /* bind_native(): the C++ nodes behind those getters and the setters, called past
     * their Python methods (jsbsim_native.h); jsb.get NULL: the Python methods are. */
    sb_jsb_api jsb;
    void *get_node[SB_FDM_SAMPLE_FIELD_COUNT];
    void *set_node[4];
    /* The pulse widths last written into JSBSim [us], and whether they were: a held
     * command is not written again (the properties are JSBSim inputs nothing else sets). */
    double pwm_written[4];
    int pwm_written_ok;
    Py_buffer buf_view;       /* the step buffer (bytearray of sb_record slots) */
    Py_buffer state_view;     /* float64[ST_COUNT] */
    Py_buffer block_view;     /* float64 (rows, 6): slow bias + white noise */
    Py_buffer temps_view;     /* float64 (rows): die temperature per step */
    Py_buffer baro_noise;     /* float64 (rows, 1): the stage reads these buffers */
    Py_buffer mag_noise;      /* float64 (rows, 3) */
    Py_buffer gnss_noise;     /* float64 (rows, 6): the C GNSS's (step_gnss.c) */
    sb_record *slots;
    Py_ssize_t n_slots;
    sb_sensor_stage stage;
    int64_t dt_ns;
    int64_t step_index;
    force_frame_t forces[2];  /* set_forces(): written before each run() */
    int n_force_frames;
    sb_batch batch;           /* bind_lockstep(): the in-process lockstep batch */
    Py_buffer raw_view;       /* bind_imu_raw(): the chip's ODR rows (step_raw.c) */
    sb_call pack_torque[4];   /* configure_battery(): bound getters of fcs/m1..4-torque-lbsft */
} Kernel;

/* stepmodule.c */
void sb_step_release(Py_buffer *v);
int sb_step_take_callables(PyObject *seq, PyObject **out, Py_ssize_t n, const char *what);
int sb_step_get_f64(PyObject *obj, Py_buffer *view, Py_ssize_t min_items, int writable,
                    const char *what);

/* step_run.c: one physics step, its records written from slot `first`; returns the
 * F_* flags or'ed with the number of records written, or -1 with an exception set. */
long sb_step_run(Kernel *self, PyObject *pwm, Py_ssize_t first);
/* The same with the four pulse widths as objects (floats or ints) [us]. */
long sb_step_run_items(Kernel *self, PyObject *const *pwm, Py_ssize_t first);

/* step_batch.c: Kernel.bind_lockstep / run_batch, and their clean-up */
PyObject *Kernel_bind_lockstep(Kernel *self, PyObject *args, PyObject *kwds);
PyObject *Kernel_run_batch(Kernel *self, PyObject *arg);
PyObject *Kernel_finish_step(Kernel *self, PyObject *arg);
void sb_batch_clear(sb_batch *b);
int sb_batch_traverse(sb_batch *b, visitproc visit, void *arg);

/* step_gnss.c: the C GNSS's methods and attributes (gnss_model.h) */
PyObject *Kernel_configure_gnss(Kernel *self, PyObject *args, PyObject *kwds);
PyObject *Kernel_set_gnss_block(Kernel *self, PyObject *args);
PyObject *Kernel_gnss_take(Kernel *self, PyObject *args);
PyObject *Kernel_gnss_give(Kernel *self, PyObject *unused);
PyObject *Kernel_get_gnss_on(Kernel *self, void *closure);
PyObject *Kernel_get_gnss_seq(Kernel *self, void *closure);

/* step_hash.c: the Blake2b type; its state, or NULL with TypeError if obj is not one */
extern PyTypeObject SbBlake2bType;
sb_blake2b *sb_step_hash_state(PyObject *obj);

/* step_config.c: configuration methods and attributes of the Kernel type */
void sb_step_clear_forces(Kernel *self);
PyObject *Kernel_set_block(Kernel *self, PyObject *args);
PyObject *Kernel_set_injected(Kernel *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *Kernel_seqs(Kernel *self, PyObject *unused);
PyObject *Kernel_configure_baro(Kernel *self, PyObject *args);
PyObject *Kernel_configure_mag(Kernel *self, PyObject *args);
PyObject *Kernel_set_baro_block(Kernel *self, PyObject *arr);
PyObject *Kernel_set_mag_block(Kernel *self, PyObject *arr);
/* Hold a (rows, width) float64 array in *held and point a low-rate sensor's noise at it,
 * read from row pos on; -1 with ValueError for another shape or a pos outside 0..rows. */
int sb_step_set_noise(sb_lowrate *lr, Py_buffer *held, PyObject *arr, Py_ssize_t width,
                      Py_ssize_t pos, const char *what);
PyObject *Kernel_hold(Kernel *self, PyObject *args);
extern PyGetSetDef sb_step_getset[];

/* step_raw.c: the chip's raw samples for the log (imu_raw.h) */
PyObject *Kernel_bind_imu_raw(Kernel *self, PyObject *rows);
PyObject *Kernel_take_imu_raw(Kernel *self, PyObject *unused);

/* step_forces.c: the disturbance forces written into JSBSim before each run() */
PyObject *Kernel_set_forces(Kernel *self, PyObject *plan);
int sb_step_apply_forces(Kernel *self, int64_t k);

/* step_faults.c: issue 28's sensor faults and a damaged prop's vibration */
PyObject *Kernel_set_imu_fault(Kernel *self, PyObject *args, PyObject *kwds);
PyObject *Kernel_set_baro_fault(Kernel *self, PyObject *args, PyObject *kwds);
PyObject *Kernel_set_mag_fault(Kernel *self, PyObject *args, PyObject *kwds);
PyObject *Kernel_set_fault_seed(Kernel *self, PyObject *arg);
PyObject *Kernel_set_imbalance_scale(Kernel *self, PyObject *args);

/* step_battery.c: the physics-side battery (battery.h) run by the step */
PyObject *Kernel_configure_battery(Kernel *self, PyObject *args, PyObject *kwds);
PyObject *Kernel_write_battery(Kernel *self, PyObject *arg);
PyObject *Kernel_battery_state(Kernel *self, PyObject *unused);
PyObject *Kernel_battery_solve(Kernel *self, PyObject *arg);
PyObject *Kernel_battery_esc_power(Kernel *self, PyObject *omega);
PyObject *Kernel_set_battery_cell(Kernel *self, PyObject *args);
PyObject *Kernel_battery_lose_charge(Kernel *self, PyObject *arg);
int sb_step_pack_load(Kernel *self, const double omega_rad_s[4]);

/* step_native.c: Kernel.bind_native (JSBSim's nodes from C) */
PyObject *Kernel_bind_native(Kernel *self, PyObject *unused);

/* The module's functions: json_reply (step_json.c: ArduPilot SITL's JSON state line),
 * imu_noise_rows (step_imu_noise.c: the IMU's noise rows of a block). */
PyObject *sb_step_json_reply(PyObject *mod, PyObject *const *args, Py_ssize_t nargs);
PyObject *sb_step_imu_noise_rows(PyObject *mod, PyObject *args);

#endif /* SB_STEP_KERNEL_H */
