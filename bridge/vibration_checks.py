"""Scenario rules of [vibration], [mount] and [imu_chip] that need more than one key (the
schema's min/max/choices hold the rest). scenario.py calls `check` with its fail(key,
problem), which raises the ScenarioError naming the key. No imports: scenario.py loads it.
"""

from __future__ import annotations

CHIP_ODRS_HZ = (1000, 2000, 4000, 8000, 16000, 32000)   # ICM-42688-P data rates we model


def check(sc, fail) -> None:
    """Cross-key rules of the three tables; fail(key, problem) raises the ScenarioError."""
    vib, mount, chip = sc.vibration, sc.mount, sc.imu_chip
    for i, order in enumerate(vib.harmonic_orders):
        if order != int(order):
            fail(f"vibration.harmonic_orders[{i}]", f"must be a whole multiple of the rotor "
                                                    f"frequency (or 0), got {order:g}")
    if chip.aaf_order not in (0, 2):
        fail("imu_chip.aaf_order", f"the ICM-42688-P's AAF is 2nd order: use 2 (on) or 0 "
                                   f"(off), got {chip.aaf_order}")
    if chip.odr_hz not in CHIP_ODRS_HZ:
        fail("imu_chip.odr_hz", f"{chip.odr_hz} Hz is not a chip data rate; use one of "
                                f"{', '.join(str(r) for r in CHIP_ODRS_HZ)}")
    nyquist = chip.odr_hz / 2.0
    for key, f_hz in (("mount.resonance_hz", mount.resonance_hz),
                      ("mount.rot_resonance_hz", mount.rot_resonance_hz),
                      ("vibration.frame_mode_hz", vib.frame_mode_hz),
                      ("imu_chip.aaf_hz", chip.aaf_hz)):
        if f_hz >= nyquist:
            fail(key, f"{f_hz:g} Hz is at or above the chip's Nyquist frequency "
                      f"(imu_chip.odr_hz / 2 = {nyquist:g} Hz); lower it or raise odr_hz")
    if not vib.enabled:
        return
    if sc.imu.rate_hz != sc.physics.rate_hz:
        fail("vibration.enabled", f"the chip pipeline reads one sample per physics step: "
                                  f"set imu.rate_hz = physics.rate_hz ({sc.physics.rate_hz})")
    if chip.odr_hz % sc.imu.rate_hz:
        fail("imu_chip.odr_hz", f"must be a whole multiple of imu.rate_hz ({sc.imu.rate_hz} Hz)")
