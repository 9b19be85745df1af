/*
 * step_kernel.h - the Kernel object of silbridge.bridge._step, shared by
 * stepmodule.c (the Python type: construction, arguments, the module),
 * step_run.c (the step itself) and step_config.c (the methods that configure
 * it between steps: noise blocks, sensors, forces).
 */
#ifndef SB_STEP_KERNEL_H
#define SB_STEP_KERNEL_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <math.h>
#include <string.h>

#include "sb_records.h"
#include "step_maths.h"

/* State slots (doubles) the kernel leaves in the Python-visible state array. */
enum {
    ST_W = 0,          /* 0..2 body rates FRD [rad/s] */
    ST_F = 3,          /* 3..5 specific force FRD [m/s^2] */
    ST_EULER = 6,      /* 6..8 phi, theta, psi [rad] */
    ST_VEL = 9,        /* 9..11 velocity NED [m/s] */
    ST_LAT = 12,       /* geodetic latitude [rad] */
    ST_LON = 13,       /* longitude [rad] */
    ST_HAGL = 14,      /* CG height above ground [m] */
    ST_OMEGA = 15,     /* 15..18 rotor speeds [rad/s] */
    ST_ON_GROUND = 19, /* 1.0 while a leg is loaded */
    ST_BARO_PA = 20,   /* lagged static pressure [Pa] */
    ST_TEMP_C = 21,    /* IMU die temperature of the last sample [degC] */
    ST_PREV_VD = 22,   /* down velocity of the step before [m/s] */
    ST_COS_TILT = 23,  /* cosine of the tilt from level */
    ST_COUNT = 24
};

/* Getter order, the contract with bridge/simulator.py (GETTERS there). */
enum {
    G_P, G_Q, G_R, G_FBX, G_FBY, G_FBZ, G_PHI, G_THETA, G_PSI, G_VN, G_VE, G_VD,
    G_LAT, G_LON, G_HAGL, G_O1, G_O2, G_O3, G_O4, G_GEAR, G_PRESSURE, G_COUNT
};

/* Constants (doubles) in the order of KERNEL_CONSTS in bridge/step_python.py. */
enum {
    C_LBF_TO_M_S2, C_FT_M, C_PSF_PA, C_LAT0, C_LON0, C_M_LAT, C_M_LON, C_AGL0,
    C_DT_S, C_INV_OMEGA_MAX2, C_VIB_A, C_VIB_G, C_RANGE_A, C_RANGE_G, C_BARO_ALPHA,
    C_COS_CRASH_TILT, C_STRIKE_AGL, C_COUNT
};

/* Returned flags: the low byte is the number of records written. */
#define F_SLOW_DUE 0x100      /* sim_ns reached next_slow_ns: baro/mag/GNSS/setpoint */
#define F_BLOCK_DONE 0x200    /* noise block used up: call set_block before the next step */
#define F_GROUND_CHANGED 0x400
#define F_TIPPED 0x800        /* on the ground, tilted past the crash tilt */
#define F_FLIPPED 0x1000      /* upside down for flip_steps steps */
#define F_ROTOR_STRIKE 0x2000
#define F_BARO_BLOCK_DONE 0x4000  /* baro noise used up: set_baro_block before the next step */
#define F_MAG_BLOCK_DONE 0x8000   /* mag noise used up: set_mag_block */

/* A 100 Hz sensor the kernel samples (lowrate.py documents the models). */
typedef struct {
    int on;                   /* configured */
    double rate_hz;
    int64_t m, next_ns;       /* sample m is due at next_ns = round(m * 1e9 / rate_hz) */
    Py_buffer noise;          /* float64 (rows, width): standard normals */
    Py_ssize_t rows, pos;
    uint32_t seq;
} lowrate_t;

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

typedef struct {
    PyObject_HEAD
    PyObject *setters[4];     /* bound set_double_value of fcs/m1..4-pwm-us */
    PyObject *run;            /* bound FGFDMExec.run */
    PyObject *getters[G_COUNT];
    Py_buffer buf_view;       /* the step buffer (bytearray of sb_record slots) */
    Py_buffer state_view;     /* float64[ST_COUNT] */
    Py_buffer block_view;     /* float64 (rows, 6): slow bias + white noise */
    Py_buffer temps_view;     /* float64 (rows): die temperature per step */
    int have_block;
    sb_record *slots;
    Py_ssize_t n_slots;
    double *st;
    double c[C_COUNT];
    sb_imu_consts imu;
    double phase[4];          /* rotor phases [rad] */
    double injected[3];       /* injected gyro bias FRD [rad/s] */
    Py_ssize_t rows, pos;     /* noise block rows, next row */
    int scalar_imu;           /* 1: one IMU sample per step, written here */
    int64_t dt_ns;
    int64_t step_index;
    int64_t next_slow_ns;
    uint32_t seq_imu, seq_att, seq_nav;
    int was_on_ground;
    double prev_vd;
    int64_t upside_down_steps, flip_steps;
    lowrate_t baro, mag;
    PyObject *get_temp;       /* bound getter of atmosphere/T-R (read when baro is due) */
    double baro_offset_pa, baro_noise_pa;
    double mag_field_ned[3], mag_offset[3], mag_noise_gauss;   /* gauss */
    force_frame_t forces[2];  /* set_forces(): written before each run() */
    int n_force_frames;
} Kernel;

/* stepmodule.c */
void sb_step_release(Py_buffer *v);
int sb_step_take_callables(PyObject *seq, PyObject **out, Py_ssize_t n, const char *what);
int sb_step_get_f64(PyObject *obj, Py_buffer *view, Py_ssize_t min_items, int writable,
                    const char *what);

/* step_run.c: one physics step, its records written from slot `first`; returns the
 * F_* flags or'ed with the number of records written, or -1 with an exception set. */
long sb_step_run(Kernel *self, PyObject *pwm, Py_ssize_t first);

/* step_config.c: configuration methods and attributes of the Kernel type */
void sb_step_clear_forces(Kernel *self);
PyObject *Kernel_set_block(Kernel *self, PyObject *args);
PyObject *Kernel_set_injected(Kernel *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *Kernel_seqs(Kernel *self, PyObject *unused);
PyObject *Kernel_configure_baro(Kernel *self, PyObject *args);
PyObject *Kernel_configure_mag(Kernel *self, PyObject *args);
PyObject *Kernel_set_baro_block(Kernel *self, PyObject *arr);
PyObject *Kernel_set_mag_block(Kernel *self, PyObject *arr);
PyObject *Kernel_set_forces(Kernel *self, PyObject *plan);
extern PyGetSetDef sb_step_getset[];

/* step_json.c: the module-level json_reply (ArduPilot SITL's JSON state line). */
extern PyMethodDef sb_step_json_methods[];

#endif /* SB_STEP_KERNEL_H */
