"""STATUS_DTYPE (Python) against fc_core_status_t (C), field by field."""

from silbridge.fc_sil import STATUS_DTYPE, _core
from silbridge.shm.records import RECORD_SIZE


def test_status_dtype_mirrors_the_c_struct():
    layout = _core.status_layout()
    assert STATUS_DTYPE.itemsize == layout["itemsize"] == _core.STATUS_SIZE
    c_names = [name for name, _, _ in layout["fields"]]
    assert list(STATUS_DTYPE.names) == c_names
    for name, offset, size in layout["fields"]:
        dt, off = STATUS_DTYPE.fields[name][:2]
        assert (off, dt.itemsize) == (offset, size), name


def test_required_fields_for_the_logs_are_present():
    required = {"sim_ns": ("i", ()), "q_est_wxyz": ("f", (4,)), "euler_est_rad": ("f", (3,)),
                "att_target_rad": ("f", (3,)), "rate_target_frd_rad_s": ("f", (3,)),
                "rate_frd_rad_s": ("f", (3,)), "pid_p": ("f", (3,)), "pid_i": ("f", (3,)),
                "pid_d": ("f", (3,)), "pid_ff": ("f", (3,)), "limited": ("u", (3,)),
                "cp_us": ("f", ()), "cr_us": ("f", ()), "cy_us": ("f", ()),
                "throttle_us": ("f", ()), "motor_us": ("f", (4,)), "sat_flags": ("u", ()),
                "trust": ("f", ()), "gyro_bias_rad_s": ("f", (3,)), "blend_w": ("f", ()),
                "alt_est_m": ("f", ()), "climb_est_m_s": ("f", ()), "alt_target_m": ("f", ()),
                "trim_us": ("f", (2,))}
    for name, (kind, shape) in required.items():
        dt = STATUS_DTYPE[name]
        assert dt.base.kind == kind and dt.shape == shape, name


def test_records_are_the_shm_contract():
    assert _core.status_layout()["sizeof_record"] == RECORD_SIZE
