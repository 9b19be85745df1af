"""The sensor stage stands alone in C: built with no Python headers and fed an FDM sample
by name (as issue 25's property-node reader will), it writes the same records, flags and
state as the Python oracle (step_kernel_oracle.py) for the same sample.

A real JSBSim sample after a hover, then the same sample tipped on the ground and upside
down in the air, so that the truth, IMU, baro, magnetometer, STEP_END and crash paths run.
"""

import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import step_kernel_oracle

from silbridge.bridge import _step
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator

ROOT = Path(__file__).resolve().parents[2]
DRIVER = Path(__file__).with_name("sensor_stage_driver.c")
SIM_NS = 10_000_000               # one 100 Hz period: baro and magnetometer are due
IMU_NOISE = (0.01, -0.02, 0.03, 0.1, -0.2, 0.3)
IMU_TEMP_C = 24.5
BARO = (100.0, 3.0, 2.0)          # rate [Hz], offset [Pa], noise [Pa]
BARO_NOISE = 0.5
MAG = (100.0, 0.21, 0.01, 0.42, 0.01, 0.02, 0.03, 0.005)  # rate, field NED, offset, noise
MAG_NOISE = (1.0, -1.0, 0.5)
PHASE = (0.1, 0.2, 0.3, 0.4)


@pytest.fixture(scope="module")
def driver(tmp_path_factory):
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    exe = tmp_path_factory.mktemp("stage") / "stage"
    src = ROOT / "bridge" / "src"
    # Only the stage, its maths and the record header: no Python include path.
    subprocess.run([cc, "-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-ffp-contract=off",
                    "-I", str(src), "-I", str(ROOT / "shm" / "include"), str(DRIVER),
                    str(src / "sensor_stage.c"), str(src / "sensor_faults.c"),
                    str(src / "step_maths.c"),
                    str(src / "vibration.c"), str(src / "imu_chip.c"),
                    str(src / "imu_raw.c"), str(src / "battery.c"),
                    str(src / "gnss_model.c"), str(src / "lowrate.c"), "-lm",
                    "-o", str(exe)], check=True, capture_output=True, text=True)
    return exe


@pytest.fixture(scope="module")
def flown():
    """A real sample and the run's constants, after 0.5 s near hover."""
    sim = Simulator(load_scenario("S1"))
    for _ in range(500):
        sim.step((sim.hover_pwm_us + 30.0,) * 4)
    sample = {name: f() for name, f in sim.fdm.sample_getters().items()}
    return sample, sim._stage_consts(), sim.baro.filtered_pa


def _csv(values) -> str:
    return ",".join(repr(float(v)) for v in values)


def _run_c(driver, sample, consts, baro_pa, next_slow_ns, flip_steps):
    args = [f"{n}={v!r}" for n, v in {**sample, **consts}.items()]
    args += [f"phase={_csv(PHASE)}", f"imu_noise={_csv(IMU_NOISE)}", f"imu_temp_c={IMU_TEMP_C!r}",
             f"baro={_csv(BARO)}", f"baro_noise={BARO_NOISE!r}", f"mag={_csv(MAG)}",
             f"mag_noise={_csv(MAG_NOISE)}",
             f"step={_csv((SIM_NS, next_slow_ns, flip_steps, baro_pa))}"]
    out = subprocess.run([str(driver), *args], check=True, capture_output=True,
                         text=True).stdout.splitlines()
    return int(out[0]), bytes.fromhex(out[1]), [float(x) for x in out[2].split()]


def _run_oracle(sample, consts, baro_pa, next_slow_ns, flip_steps):
    buf = bytearray(8 * 64)
    state = np.zeros(_step.ST_COUNT)
    state[_step.ST_BARO_PA] = baro_pa
    noop = lambda *a: None  # noqa: E731 - JSBSim's setters and run(): the sample is given
    k = step_kernel_oracle.Kernel(buf, [noop] * 4, noop,
                                  {n: (lambda v=v: v) for n, v in sample.items()}, state,
                                  consts, PHASE, SIM_NS, flip_steps, True, False)
    k.set_block(np.array([IMU_NOISE]), np.array([IMU_TEMP_C]))
    k.configure_baro(*BARO)
    k.configure_mag(MAG[0], MAG[1:4], MAG[4:7], MAG[7])
    k.set_baro_block(np.array([[BARO_NOISE]]))
    k.set_mag_block(np.array([MAG_NOISE]))
    k.next_slow_ns = next_slow_ns
    flags = k.step((1000.0,) * 4)
    return flags, bytes(buf[:(flags & 0xFF) * 64]), state.tolist()


CASES = {
    # name: (changes to the flown sample, next_slow_ns, flip_steps, flags expected)
    "hover": ({}, 10**12, 100, 0),
    # hagl_ft: the height above ground, set as the geodetic altitude over the terrain
    "tipped on the ground": ({"phi_rad": 1.2, "hagl_ft": 0.3, "gear_contacts": 1.0}, 0, 100,
                             _step.F_SLOW_DUE | _step.F_TIPPED | _step.F_ROTOR_STRIKE
                             | _step.F_GROUND_CHANGED),
    "upside down": ({"phi_rad": 3.0}, 0, 1, _step.F_SLOW_DUE | _step.F_FLIPPED),
}


@pytest.mark.parametrize("case", CASES)
def test_the_c_stage_alone_writes_what_the_oracle_writes(driver, flown, case):
    change, next_slow_ns, flip_steps, expected = CASES[case]
    sample, consts, baro_pa = flown
    change = dict(change)
    if "hagl_ft" in change:
        change["geod_alt_ft"] = consts["terrain_ft"] + change.pop("hagl_ft")
    sample = {**sample, **change}
    c_flags, c_bytes, c_state = _run_c(driver, sample, consts, baro_pa, next_slow_ns, flip_steps)
    o_flags, o_bytes, o_state = _run_oracle(sample, consts, baro_pa, next_slow_ns, flip_steps)
    assert c_flags == o_flags
    # One noise row each: every block is used up, as the flags tell.
    used_up = _step.F_BLOCK_DONE | _step.F_BARO_BLOCK_DONE | _step.F_MAG_BLOCK_DONE
    assert c_flags & ~0xFF == expected | used_up
    assert c_flags & 0xFF == 5            # IMU, GT_ATT, GT_NAV, BARO, MAG
    assert c_bytes == o_bytes
    assert c_state == o_state
    kinds = np.frombuffer(c_bytes, dtype="<u2").reshape(5, 32)[:, 0].tolist()
    assert kinds == [1, 5, 6, 2, 3]
    step_end = np.frombuffer(c_bytes, dtype="<u2").reshape(5, 32)[-1, 1]
    assert step_end == (0 if expected & _step.F_SLOW_DUE else 1)
    assert math.isclose(c_state[_step.ST_HAGL],
                        (sample["geod_alt_ft"] - consts["terrain_ft"]) * 0.3048)
