/*
 * sensor_stage.c - see sensor_stage.h. One step: convert the FDM sample to SI truth,
 * write the scalar IMU record, the ground truth, leave the state for Python, judge
 * contact and crashes, then the baro and magnetometer records when due, the held GNSS
 * fixes and the battery's report (battery.h). The order of the records is the contract's
 * (on a step Python finishes, its GNSS and SETPOINT come before the battery's); every
 * expression keeps the association of the Python oracle.
 */
#include "sensor_stage.h"

#include <math.h>
#include <string.h>

#define SAMPLE(f) {#f, offsetof(sb_fdm_sample, f)}
const sb_named_double SB_FDM_SAMPLE_FIELDS[SB_FDM_SAMPLE_FIELD_COUNT] = {
    SAMPLE(p_rad_s), SAMPLE(q_rad_s), SAMPLE(r_rad_s),
    SAMPLE(fbx_lbf), SAMPLE(fby_lbf), SAMPLE(fbz_lbf),
    SAMPLE(phi_rad), SAMPLE(theta_rad), SAMPLE(psi_rad),
    SAMPLE(vn_ft_s), SAMPLE(ve_ft_s), SAMPLE(vd_ft_s),
    SAMPLE(lat_rad), SAMPLE(lon_rad), SAMPLE(geod_alt_ft),
    {"omega1_rad_s", offsetof(sb_fdm_sample, omega_rad_s[0])},
    {"omega2_rad_s", offsetof(sb_fdm_sample, omega_rad_s[1])},
    {"omega3_rad_s", offsetof(sb_fdm_sample, omega_rad_s[2])},
    {"omega4_rad_s", offsetof(sb_fdm_sample, omega_rad_s[3])},
    SAMPLE(gear_contacts), SAMPLE(pressure_psf), SAMPLE(temperature_r)};
#undef SAMPLE

#define CONST(f) {#f, offsetof(sb_stage_consts, f)}
#define IMU_CONST(f) {#f, offsetof(sb_stage_consts, imu.f)}
const sb_named_double SB_STAGE_CONST_FIELDS[SB_STAGE_CONST_FIELD_COUNT] = {
    CONST(lbf_to_m_s2), CONST(ft_m), CONST(psf_pa), CONST(lat0_rad), CONST(lon0_rad),
    CONST(m_per_rad_lat), CONST(m_per_rad_lon), CONST(agl0_m), CONST(baro_alpha),
    CONST(cos_crash_tilt), CONST(strike_agl_m), CONST(terrain_ft),
    IMU_CONST(dt_s), IMU_CONST(inv_omega_max2), IMU_CONST(vib_accel), IMU_CONST(vib_gyro),
    IMU_CONST(range_accel), IMU_CONST(range_gyro),
    /* issue 26: bridge/vibration_consts.py fills these (all 0 with vibration off and no
     * IMU misalignment) */
#define V(name, f) {name, offsetof(sb_stage_consts, vib.f)}
#define HUB(m, i) V("vib_hub" #m "_x_m", hub_frd_m[i][0]), \
    V("vib_hub" #m "_y_m", hub_frd_m[i][1]), V("vib_hub" #m "_z_m", hub_frd_m[i][2]), \
    V("vib_spin" #m, spin_cw[i]), V("vib_imbalance" #m "_kg_m", imbalance_kg_m[i])
#define RIPPLE(h, i) V("vib_ripple" #h "_order", ripple_order[i]), \
    V("vib_ripple" #h "_frac", ripple_frac[i])
    V("vib_on", on), HUB(1, 0), HUB(2, 1), HUB(3, 2), HUB(4, 3), V("vib_kt_n_s2", kt_n_s2),
    RIPPLE(1, 0), RIPPLE(2, 1), RIPPLE(3, 2), RIPPLE(4, 3), RIPPLE(5, 4),
    V("vib_mass_kg", mass_kg), V("vib_ixx_kg_m2", inertia_kg_m2[0]),
    V("vib_iyy_kg_m2", inertia_kg_m2[1]), V("vib_izz_kg_m2", inertia_kg_m2[2]),
    V("vib_lever_x_m", imu_lever_frd_m[0]), V("vib_lever_y_m", imu_lever_frd_m[1]),
    V("vib_lever_z_m", imu_lever_frd_m[2]), V("vib_frame_hz", frame_hz),
    V("vib_frame_damping", frame_damping), V("vib_mount_hz", mount_hz),
    V("vib_mount_damping", mount_damping), V("vib_mount_rot_hz", mount_rot_hz),
    V("vib_mount_rot_damping", mount_rot_damping),
    V("vib_wash_frac", wash_frac), V("vib_wash_seed", wash_seed),
    {"chip_odr_hz", offsetof(sb_stage_consts, chip.odr_hz)},
    {"chip_aaf_hz", offsetof(sb_stage_consts, chip.aaf_hz)},
    {"chip_aaf_order", offsetof(sb_stage_consts, chip.aaf_order)},
#define ROT(ij, k) {"imu_r" #ij, offsetof(sb_stage_consts, imu_rot[k])}
    {"imu_rot_on", offsetof(sb_stage_consts, imu_rot_on)},
    ROT(00, 0), ROT(01, 1), ROT(02, 2), ROT(10, 3), ROT(11, 4), ROT(12, 5), ROT(20, 6),
    ROT(21, 7), ROT(22, 8)};
#undef CONST
#undef IMU_CONST
#undef V
#undef HUB
#undef RIPPLE
#undef ROT

/* Every double of the two structs is named once: a field added without a name fails here. */
_Static_assert(sizeof(sb_fdm_sample) == SB_FDM_SAMPLE_FIELD_COUNT * sizeof(double),
               "name every sb_fdm_sample field in SB_FDM_SAMPLE_FIELDS");
_Static_assert(sizeof(sb_stage_consts) == SB_STAGE_CONST_FIELD_COUNT * sizeof(double),
               "name every sb_stage_consts field in SB_STAGE_CONST_FIELDS");

/* The sample in SI units and the frames the records carry. */
typedef struct {
    double w[3];       /* body rates FRD [rad/s] */
    double af[3];      /* specific force FRD [m/s^2] */
    double vel[3];     /* velocity NED [m/s] */
    double pos[3];     /* position NED about home [m], down on the whole-mm grid */
    double q[4];       /* attitude (w, x, y, z), w >= 0 */
    double hagl_m;     /* CG height above ground */
    int on_ground;
} truth_t;

void sb_sensor_stage_init(sb_sensor_stage *s, const sb_stage_consts *c, double *state,
                          const double phase_rad[4], int64_t flip_steps, int scalar_imu,
                          int on_ground)
{
    memset(s, 0, sizeof *s);
    s->c = *c;
    s->state = state;
    memcpy(s->phase_rad, phase_rad, sizeof s->phase_rad);
    s->flip_steps = flip_steps;
    s->scalar_imu = scalar_imu;
    s->was_on_ground = on_ground;
    if (c->vib.on != 0.0) {
        sb_vib_init(&s->vib, &c->vib, phase_rad);
        sb_chip_init(&s->chip, &c->chip);
        const double n = c->chip.odr_hz * c->imu.dt_s;
        s->chip_n = n >= 1.0 ? (int)lround(n) : 1;
        sb_chip_ramp_init(&s->chip, s->chip_n);
    }
}

void sb_sensor_stage_set_imu_noise(sb_sensor_stage *s, const double *noise,
                                   const double *temp_c, size_t rows)
{
    s->imu_noise = noise;
    s->imu_temp_c = temp_c;
    s->imu_rows = rows;
    s->imu_pos = 0;
}

const char *sb_sensor_stage_error(long code)
{
    switch (code) {
    case SB_STAGE_NO_IMU_NOISE:
        return "no IMU noise block: call set_block first";
    case SB_STAGE_BUFFER_FULL:
        return "step buffer too small for the ground truth, baro and mag records";
    case SB_STAGE_NO_BARO_NOISE:
        return "no baro noise: call set_baro_block first";
    case SB_STAGE_NO_MAG_NOISE:
        return "no mag noise: call set_mag_block first";
    case SB_STAGE_NO_GNSS_NOISE:
        return "no GNSS noise: call set_gnss_block before the next epoch";
    case SB_STAGE_GNSS_HELD_FULL:
        return "GNSS fixes held past SB_HELD_MAX: the C GNSS needs latency_s x rate_hz + 2 "
               "<= SB_HELD_MAX (gnss_kernel.py takes it only then)";
    default:
        return "unknown sensor stage error";
    }
}

static void header(sb_record *r, uint16_t kind, uint32_t seq, int64_t sim_ns)
{
    r->h.kind = kind;
    r->h.flags = 0;
    r->h.seq = seq;
    r->h.sim_ns = sim_ns;
    r->h.wall_ns = 0;
}

/* JSBSim's feet, pounds and geodetic angles to SI truth in NED/FRD (and the baro lag). */
static void to_truth(sb_sensor_stage *s, const sb_fdm_sample *in, truth_t *t)
{
    const sb_stage_consts *c = &s->c;
    double *st = s->state;
    t->w[0] = in->p_rad_s;
    t->w[1] = in->q_rad_s;
    t->w[2] = in->r_rad_s;
    const double lbf = c->lbf_to_m_s2;
    t->af[0] = in->fbx_lbf * lbf;
    t->af[1] = in->fby_lbf * lbf;
    t->af[2] = in->fbz_lbf * lbf;
    const double ft = c->ft_m;
    t->vel[0] = in->vn_ft_s * ft;
    t->vel[1] = in->ve_ft_s * ft;
    t->vel[2] = in->vd_ft_s * ft;
    t->hagl_m = (in->geod_alt_ft - c->terrain_ft) * ft;
    t->on_ground = in->gear_contacts > 0.0;
    st[ST_BARO_PA] += c->baro_alpha * (in->pressure_psf * c->psf_pa - st[ST_BARO_PA]);
    sb_quat_from_euler(in->phi_rad, in->theta_rad, in->psi_rad, t->q);
    t->pos[0] = (in->lat_rad - c->lat0_rad) * c->m_per_rad_lat;
    t->pos[1] = (in->lon_rad - c->lon0_rad) * c->m_per_rad_lon;
    t->pos[2] = sb_quant_down_m(c->agl0_m - t->hagl_m);
}

static void cross(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

/* With vibration on: what the chip puts in its register at the end of the step: the
 * rigid-body motion at the IMU (accel with the lever-arm terms alpha x r + w x (w x r),
 * alpha from the step's change of w), interpolated over the step and run through the AAF
 * at the ODR, plus each vibration line times the AAF's gain at its frequency.
 * af, w: the IMU's "true" signal; bias, noise and clipping follow in sb_imu_scalar. */
static void chip_read(sb_sensor_stage *s, const sb_fdm_sample *in, const truth_t *t,
                      double af[3], double w[3], int64_t sim_ns)
{
    const sb_stage_consts *c = &s->c;
    const double *r = c->vib.imu_lever_frd_m;
    double cur[6];
    const double *prev_w = s->chip_primed ? s->prev6 + 3 : t->w;
    double al[3], wr[3], wwr[3];
    for (int i = 0; i < 3; i++)
        al[i] = (t->w[i] - prev_w[i]) / c->imu.dt_s;
    cross(t->w, r, wr);
    cross(t->w, wr, wwr);
    cross(al, r, cur);
    for (int i = 0; i < 3; i++) {
        cur[i] += t->af[i] + wwr[i];
        cur[i + 3] = t->w[i];
    }
    if (!s->chip_primed) {
        memcpy(s->prev6, cur, sizeof s->prev6);
        sb_chip_settle(&s->chip, cur);
        s->chip_primed = 1;
    }
    if (s->raw.rows != NULL)   /* the ODR samples for the log, from copies (imu_raw.h) */
        sb_imu_raw_step(&s->raw, &s->chip, &s->vib, s->prev6, cur, in->omega_rad_s, sim_ns);
    double y[6];   /* the rigid-body motion, chip_n samples through the AAF at the ODR */
    sb_chip_ramp(&s->chip, s->prev6, cur, y);
    /* the vibration lines through the AAF, read at the step's end (vibration.h: exact) */
    sb_vib_step(&s->vib, in->omega_rad_s, c->imu.dt_s, &s->chip, y);
    memcpy(s->prev6, cur, sizeof s->prev6);
    memcpy(af, y, 3 * sizeof *af);
    memcpy(w, y + 3, 3 * sizeof *w);
}

/* v_imu = R v_body, in place (the IMU's mounting misalignment). */
static void rotate(const double r[9], double v[3])
{
    const double x = r[0] * v[0] + r[1] * v[1] + r[2] * v[2];
    const double y = r[3] * v[0] + r[4] * v[1] + r[5] * v[2];
    v[2] = r[6] * v[0] + r[7] * v[1] + r[8] * v[2];
    v[0] = x;
    v[1] = y;
}

/* The one-per-step IMU sample into *r, from the next noise row. */
static long write_imu(sb_sensor_stage *s, const sb_fdm_sample *in, const truth_t *t,
                      sb_record *r, int64_t sim_ns)
{
    if (s->imu_noise == NULL || s->imu_pos >= s->imu_rows)
        return SB_STAGE_NO_IMU_NOISE;
    long flags = 0;
    const double *stoch = s->imu_noise + 6 * s->imu_pos;
    const double temp_c = s->imu_temp_c[s->imu_pos];
    if (++s->imu_pos >= s->imu_rows)
        flags |= F_BLOCK_DONE;
    double out[6];
    double af[3], w[3];   /* the IMU's true signal: the truth (bytes as before issue 26) */
    if (s->c.vib.on != 0.0) {   /* or, Python zeroing imu.vib_*, what the chip reads */
        chip_read(s, in, t, af, w, sim_ns);
    } else {
        memcpy(af, t->af, sizeof af);
        memcpy(w, t->w, sizeof w);
    }
    if (s->c.imu_rot_on != 0.0) {
        rotate(s->c.imu_rot, af);
        rotate(s->c.imu_rot, w);
    }
    sb_imu_scalar(&s->c.imu, af, w, in->omega_rad_s, s->phase_rad, stoch, s->injected_rad_s,
                  out);
    if (s->faults.imu_on)
        sb_faults_imu(&s->faults, out);
    s->state[ST_TEMP_C] = temp_c;
    header(r, SB_KIND_IMU, s->seq_imu++, sim_ns);
    for (int i = 0; i < 3; i++) {
        r->u.imu.accel_frd_m_s2[i] = (float)out[i];
        r->u.imu.gyro_frd_rad_s[i] = (float)out[i + 3];
    }
    r->u.imu.temperature_c = (float)temp_c;
    r->u.imu.sample_index = 0;
    r->u.imu.samples_per_step = 1;
    r->u.imu.reserved = 0;
    return flags;
}

/* GT_ATT then GT_NAV into ra, rn. */
static void write_truth(sb_sensor_stage *s, const truth_t *t, sb_record *ra, sb_record *rn,
                        int64_t sim_ns)
{
    header(ra, SB_KIND_GT_ATT, s->seq_att++, sim_ns);
    for (int i = 0; i < 4; i++)
        ra->u.gt_att.q_wxyz[i] = (float)t->q[i];
    for (int i = 0; i < 3; i++) {
        ra->u.gt_att.rates_frd_rad_s[i] = (float)t->w[i];
        ra->u.gt_att.specific_force_frd_m_s2[i] = (float)t->af[i];
    }
    header(rn, SB_KIND_GT_NAV, s->seq_nav++, sim_ns);
    memset(rn->u.raw, 0, sizeof rn->u.raw);
    for (int i = 0; i < 3; i++) {
        rn->u.gt_nav.pos_ned_m[i] = t->pos[i];
        /* Truth as HIL_STATE_QUATERNION carries it (whole mm, whole cm/s) on every transport. */
        rn->u.gt_nav.vel_ned_m_s[i] = (float)sb_quant_velocity_m_s(t->vel[i]);
    }
    rn->u.gt_nav.on_ground = (uint8_t)t->on_ground;
}

/* The state Python's low-rate sensors, summaries and the block IMU path read. */
static void leave_state(double *st, const sb_fdm_sample *in, const truth_t *t)
{
    for (int i = 0; i < 3; i++) {
        st[ST_W + i] = t->w[i];
        st[ST_F + i] = t->af[i];
        st[ST_VEL + i] = t->vel[i];
    }
    st[ST_EULER] = in->phi_rad;
    st[ST_EULER + 1] = in->theta_rad;
    st[ST_EULER + 2] = in->psi_rad;
    st[ST_LAT] = in->lat_rad;
    st[ST_LON] = in->lon_rad;
    st[ST_HAGL] = t->hagl_m;
    for (int i = 0; i < 4; i++)
        st[ST_OMEGA + i] = in->omega_rad_s[i];
    st[ST_ON_GROUND] = t->on_ground;
}

/* Ground contact and crash detection; Python words the messages. */
static long contact_and_crash(sb_sensor_stage *s, const sb_fdm_sample *in, const truth_t *t)
{
    double *st = s->state;
    long flags = 0;
    st[ST_PREV_VD] = s->prev_vd_m_s;
    if (t->on_ground != s->was_on_ground) {
        flags |= F_GROUND_CHANGED;
        s->was_on_ground = t->on_ground;
    }
    s->prev_vd_m_s = t->vel[2];
    const double cos_tilt = 1.0 - 2.0 * (t->q[1] * t->q[1] + t->q[2] * t->q[2]);
    st[ST_COS_TILT] = cos_tilt;
    if (t->on_ground && cos_tilt < s->c.cos_crash_tilt)
        flags |= F_TIPPED;
    if (cos_tilt < 0.0) {
        if (++s->upside_down_steps >= s->flip_steps)
            flags |= F_FLIPPED;
    } else {
        s->upside_down_steps = 0;
    }
    if (t->hagl_m < s->c.strike_agl_m && sb_rotor_strike(in->phi_rad, in->theta_rad, t->hagl_m))
        flags |= F_ROTOR_STRIKE;
    return flags;
}

/* Start the record of a due low-rate sensor: its next noise row (NULL: none left, the
 * caller's error), its next sample time, the record's header and a zeroed payload. */
static const double *start_sample(sb_lowrate *lr, size_t width, long done_flag,
                                  uint16_t kind, sb_record *r, int64_t sim_ns, long *flags)
{
    const double *n = sb_lowrate_take(lr, width);
    if (n == NULL)
        return NULL;
    if (sb_lowrate_spent(lr))
        *flags |= done_flag;
    header(r, kind, lr->seq++, sim_ns);
    memset(r->u.raw, 0, sizeof r->u.raw);
    return n;
}

/* A due sample of a silent sensor (a fault): its schedule and noise run on as if it were
 * written, so the stream after the fault is the fault-free run's; no record, no seq. */
static long skip_sample(sb_lowrate *lr, long done_flag, long no_noise)
{
    if (sb_lowrate_take(lr, 0) == NULL)   /* width 0: the row is skipped, not read */
        return no_noise;
    return sb_lowrate_spent(lr) ? done_flag : 0;
}

static long write_baro(sb_sensor_stage *s, const sb_fdm_sample *in, sb_record *r,
                       int64_t sim_ns)
{
    long flags = 0;
    const double *n =
        start_sample(&s->baro, 1, F_BARO_BLOCK_DONE, SB_KIND_BARO, r, sim_ns, &flags);
    if (n == NULL)
        return SB_STAGE_NO_BARO_NOISE;
    double pa = s->state[ST_BARO_PA] + s->baro_offset_pa + s->baro_noise_pa * n[0];
    if (s->faults.baro.on)
        pa = sb_faults_baro_pa(&s->faults.baro, pa, in->temperature_r / 1.8, sim_ns);
    r->u.baro.pressure_pa = (float)sb_quant_pressure_pa(pa);
    r->u.baro.temperature_c = (float)(in->temperature_r / 1.8 - 273.15);
    return flags;
}

static long write_mag(sb_sensor_stage *s, const sb_fdm_sample *in, sb_record *r,
                      int64_t sim_ns)
{
    long flags = 0;
    const double *n = start_sample(&s->mag, 3, F_MAG_BLOCK_DONE, SB_KIND_MAG, r, sim_ns, &flags);
    if (n == NULL)
        return SB_STAGE_NO_MAG_NOISE;
    double b[3];
    sb_ned_to_frd(in->phi_rad, in->theta_rad, in->psi_rad, s->mag_field_ned_gauss, b);
    for (int i = 0; i < 3; i++)
        r->u.mag.field_frd_gauss[i] =
            (float)(b[i] + s->mag_offset_gauss[i] + s->mag_noise_gauss * n[i]);
    return flags;
}

/* The C GNSS's epoch due at sim_ns: its fix made and held to its release (before the held
 * records are written, so a fix released at its epoch follows the older ones, as Python's
 * did). Flags, or a negative SB_STAGE_* code. */
static long gnss_epoch(sb_sensor_stage *s, const sb_fdm_sample *in, const truth_t *t,
                       int64_t sim_ns)
{
    sb_gnss_model *g = &s->gnss;
    const sb_gnss_truth truth = {in->lat_rad, in->lon_rad, t->hagl_m,
                                 {t->vel[0], t->vel[1], t->vel[2]}};
    sb_record r;
    const int rc = sb_gnss_epoch(g, &truth, sim_ns, &r);
    if (rc < 0)
        return SB_STAGE_NO_GNSS_NOISE;
    if (sb_sensor_stage_hold(s, &r, sim_ns + g->c.latency_ns) < 0)
        return SB_STAGE_GNSS_HELD_FULL;
    return rc ? F_GNSS_BLOCK_DONE : 0;
}

int sb_sensor_stage_hold(sb_sensor_stage *s, const sb_record *r, int64_t due_ns)
{
    sb_held *h = &s->held;
    if (h->n >= SB_HELD_MAX)
        return -1;
    const int i = (h->head + h->n++) % SB_HELD_MAX;
    h->rec[i] = *r;
    h->due_ns[i] = due_ns;
    return 0;
}

/* The held records due at sim_ns into slots[*slot..]; SB_STAGE_BUFFER_FULL if no room. */
static long write_held(sb_sensor_stage *s, sb_record *slots, size_t n_slots, size_t *slot,
                       int64_t sim_ns)
{
    sb_held *h = &s->held;
    while (h->n > 0 && sim_ns >= h->due_ns[h->head]) {
        if (*slot >= n_slots)
            return SB_STAGE_BUFFER_FULL;
        sb_record *r = &slots[(*slot)++];
        *r = h->rec[h->head];
        r->h.sim_ns = sim_ns;
        r->h.flags = 0;
        h->head = (h->head + 1) % SB_HELD_MAX;
        h->n--;
    }
    return 0;
}

long sb_sensor_stage_step(sb_sensor_stage *s, const sb_fdm_sample *in, int64_t sim_ns,
                          sb_record *slots, size_t n_slots, size_t first)
{
    truth_t t;
    to_truth(s, in, &t);
    long flags = 0, f;
    size_t slot = first;
    if (s->scalar_imu) {
        if ((f = write_imu(s, in, &t, &slots[slot++], sim_ns)) < 0)
            return f;
        flags |= f;
    }
    if (slot + 4 > n_slots)   /* GT_ATT, GT_NAV, and room for baro and mag */
        return SB_STAGE_BUFFER_FULL;
    write_truth(s, &t, &slots[slot], &slots[slot + 1], sim_ns);
    slot += 2;
    leave_state(s->state, in, &t);
    flags |= contact_and_crash(s, in, &t);
    if (sb_sensor_stage_baro_due(s, sim_ns)) {
        if ((f = write_baro(s, in, &slots[slot++], sim_ns)) < 0)
            return f;
        flags |= f;
    }
    if (s->mag.on && sim_ns >= s->mag.next_ns) {
        f = s->faults.mag_off ? skip_sample(&s->mag, F_MAG_BLOCK_DONE, SB_STAGE_NO_MAG_NOISE)
                              : write_mag(s, in, &slots[slot++], sim_ns);
        if (f < 0)
            return f;
        flags |= f;
    }
    if (s->gnss.in_c && sim_ns >= s->gnss.lr.next_ns) {
        if ((f = gnss_epoch(s, in, &t, sim_ns)) < 0)
            return f;
        flags |= f;
    }
    if (s->held.n > 0 && (f = write_held(s, slots, n_slots, &slot, sim_ns)) < 0)
        return f;
    if (sb_sensor_stage_pack_due(s, sim_ns)) {
        if (slot >= n_slots)
            return SB_STAGE_BUFFER_FULL;
        sb_pack_report(&s->pack, &slots[slot++], sim_ns);
    }
    if (sim_ns >= s->next_slow_ns)
        flags |= F_SLOW_DUE;
    else   /* nothing more this step: the last record closes it */
        slots[slot - 1].h.flags = SB_FLAG_STEP_END;
    return flags | (long)(slot - first);
}
