"""The control law stands without a core, as PX4's RateControl does.

control_alone.c is compiled with fc_control.c, the blocks it steps and their headers, copied
alone into a scratch directory: no fc_core.h/.c, no parameter table (fc_params, fc_config_map),
no estimator. It configures the law by hand, sets the vehicle state and steps it; the test
checks what the steps must do.
"""

import shutil
import subprocess
from pathlib import Path

import pytest

import silbridge.fc_sil as fc_pkg

CORE = Path(fc_pkg.__file__).resolve().parent / "core"
HERE = Path(__file__).resolve().parent
# What the control law needs, and nothing else: the blocks it steps, the vehicle state it reads
# (with the attitude-error blend), the spool's "flight wanted", and the headers they share.
LAW_SOURCES = ("fc_control", "fc_rate_pid", "fc_filter", "fc_shaper", "fc_attitude", "fc_trim",
               "fc_alt_ctrl", "fc_sysid", "fc_vehicle_state", "fc_blend", "fc_spool")
LAW_HEADERS = ("fc_math.h", "fc_status.h", "fc_inputs.h", "fc_mixer.h")
FLAGS = ["-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-Wconversion",
         "-Wdouble-promotion", "-Wshadow"]

# The configuration of control_alone.c.
ANG_P = 4.5            # ATC_ANG_RLL_P [1/s]
RATE_KP = RATE_KI = 0.135  # ATC_RAT_RLL_P, _I
US_PER_UNIT = 500.0    # half the PWM range 1000..2000 [us]
PWM_MIN, SPIN_ARM, HOVER = 1000.0, 0.1, 0.35
TILT = 0.1             # the roll the cases start from [rad]


@pytest.fixture(scope="module")
def steps(tmp_path_factory):
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no host C compiler")
    work = tmp_path_factory.mktemp("control_alone")
    for name in LAW_SOURCES:
        shutil.copy(CORE / f"{name}.c", work)
        shutil.copy(CORE / f"{name}.h", work)
    for name in LAW_HEADERS:
        shutil.copy(CORE / name, work)
    shutil.copy(HERE / "control_alone.c", work)
    exe = work / "control_alone"
    build = subprocess.run([cc, *FLAGS, "-I", str(work), *sorted(map(str, work.glob("*.c"))),
                            "-lm", "-o", str(exe)], capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, check=True)
    return {name: [float(v) for v in values]
            for name, *values in (line.split() for line in run.stdout.splitlines())}


def test_a_roll_error_commands_a_roll_back_and_nothing_else(steps):
    err, rate_target, p_us, cr_us, cp_us, cy_us = steps["tilt"]
    assert err == pytest.approx(-TILT, rel=1e-3)
    assert rate_target == pytest.approx(ANG_P * err, rel=1e-6)
    assert p_us == pytest.approx(RATE_KP * rate_target * US_PER_UNIT, rel=1e-6)
    assert cr_us < 0.0 and cr_us == pytest.approx(p_us, rel=0.01)  # I and D still small
    assert cp_us == 0.0 and cy_us == 0.0


def test_the_integrator_grows_only_in_flight_and_not_into_a_saturation(steps):
    i_us, limited = steps["wind_flight"]
    assert i_us == pytest.approx(RATE_KI * ANG_P * -TILT * 1.0 * US_PER_UNIT, rel=0.01)  # 1 s
    assert limited == 0
    assert steps["wind_saturated"] == [0.0, 1.0]  # the mixer's roll flag holds it
    assert steps["wind_ground"] == [0.0, 0.0]     # no ground wind-up


def test_the_throttle_path_follows_the_flight_phase(steps):
    assert steps["shut_down"] == [PWM_MIN]
    assert steps["ground_idle"] == [pytest.approx(PWM_MIN + SPIN_ARM * 1000.0)]
    assert steps["hover"] == [pytest.approx(PWM_MIN + HOVER * 1000.0)]  # feed-forward alone
    assert steps["climb"][0] > steps["hover"][0]
