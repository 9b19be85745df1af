"""The GCS and radio failsafes on sim time, as ArduCopter SITL times them, with FS_OPTIONS
(docs/reference/failsafes.md): FailsafeMonitor driven step by step with synthetic sim time,
a stand-in for the server's heartbeat count and the real PilotInput, so the wall clock plays
no part (a lockstep run at --speed 10 meets them at the same sim time as at --speed 1)."""

from __future__ import annotations

from types import SimpleNamespace

from silbridge.fc_sil.failsafe import FailsafeMonitor
from silbridge.fc_sil.nav_config import NavConfig
from silbridge.fc_sil.params import PARAMS
from silbridge.fc_sil.pilot import PilotInput
from silbridge.fc_sil.rc_input import RcConfig
from silbridge.mavlink.gcs.vehicle_api import CopterMode

STEP_NS = 20_000_000        # the outer loop's 50 Hz


class _Flying:
    """What the GCS check reads of a vehicle flying GUIDED with a GCS link."""

    def __init__(self, mode=CopterMode.GUIDED, **params):
        values = {p.name: p.default for p in PARAMS}
        values.update(params)
        self.cfg = NavConfig.from_store(values.__getitem__)
        self.store = SimpleNamespace(host=values.__getitem__)
        self.pilot = PilotInput()
        self.pilot.configure(RcConfig.from_params(values.__getitem__))
        self.server = SimpleNamespace(gcs_heartbeats=0)
        self.sim_ns = 0
        self.armed = self.airborne = True
        self.home_set = True
        self.mode = SimpleNamespace(number=mode)
        self.texts: list = []

    def position_ok(self) -> bool:
        return True

    def statustext(self, severity, text) -> None:
        self.texts.append((self.sim_ns, text))

    def set_mode_internal(self, mode, why) -> None:
        self.mode = SimpleNamespace(number=mode)


def _fly(v: _Flying, fs: FailsafeMonitor, seconds: float, beat_every_s: float | None) -> None:
    """Step the GCS check for `seconds` of sim time, a heartbeat every beat_every_s
    (v.beat_ns: the last one)."""
    next_beat = v.sim_ns
    end = v.sim_ns + int(seconds * 1e9)
    while v.sim_ns < end:
        v.sim_ns += STEP_NS
        if beat_every_s is not None and v.sim_ns >= next_beat:
            v.server.gcs_heartbeats += 1
            v.beat_ns = v.sim_ns
            next_beat = v.sim_ns + int(beat_every_s * 1e9)
        fs.check_links(v)


def test_silence_is_timed_on_sim_time_and_returns_home():
    v, fs = _Flying(FS_GCS_ENABLE=1, FS_GCS_TIMEOUT=5.0), FailsafeMonitor()
    _fly(v, fs, 30.0, 1.0)
    assert not fs.gcs and v.mode.number == CopterMode.GUIDED
    last_beat_ns = v.beat_ns
    _fly(v, fs, (last_beat_ns + 4.9e9 - v.sim_ns) / 1e9, None)
    assert not fs.gcs                     # 4.9 s of sim silence < FS_GCS_TIMEOUT
    _fly(v, fs, 1.0, None)
    assert fs.gcs and v.mode.number == CopterMode.RTL
    t, text = v.texts[0]
    assert text == "GCS Failsafe"
    assert 5.0 < (t - last_beat_ns) / 1e9 <= 5.0 + STEP_NS / 1e9
    _fly(v, fs, 1.0, 1.0)                 # heard again: cleared, stays in RTL
    assert not fs.gcs and v.texts[-1][1] == "GCS Failsafe Cleared"
    assert v.mode.number == CopterMode.RTL


def test_heartbeats_sparser_than_the_timeout_fire_it():
    """A ground station heartbeating at 1 Hz of wall time in a run at --speed 10 is silent
    for 10 s of sim time between beats: past FS_GCS_TIMEOUT, as on ArduCopter SITL."""
    v, fs = _Flying(FS_GCS_ENABLE=1, FS_GCS_TIMEOUT=5.0), FailsafeMonitor()
    _fly(v, fs, 30.0, 10.0)
    assert ("GCS Failsafe" in [t for _, t in v.texts]) and v.mode.number == CopterMode.RTL


def test_off_by_default_as_arducopter_and_silent_before_any_heartbeat():
    v, fs = _Flying(), FailsafeMonitor()
    assert v.cfg.fs_gcs_enable == 0
    _fly(v, fs, 5.0, 1.0)
    _fly(v, fs, 30.0, None)
    assert not fs.gcs and not v.texts and v.mode.number == CopterMode.GUIDED
    v2, fs2 = _Flying(FS_GCS_ENABLE=1), FailsafeMonitor()
    _fly(v2, fs2, 30.0, None)             # no GCS ever heard: nothing to lose
    assert not fs2.gcs and not v2.texts


def test_a_pilot_flown_mode_goes_on_through_a_gcs_failsafe_by_default():
    """FS_OPTIONS 16 (ArduCopter's default): LOITER goes on, announced; 0: it returns."""
    for options, mode_after, text in ((16, CopterMode.LOITER,
                                       "GCS Failsafe - Continuing Pilot Control"),
                                      (0, CopterMode.RTL, "GCS Failsafe")):
        v, fs = _Flying(CopterMode.LOITER, FS_GCS_ENABLE=1, FS_OPTIONS=options), FailsafeMonitor()
        _fly(v, fs, 3.0, 1.0)
        _fly(v, fs, 10.0, None)
        assert v.mode.number == mode_after and v.texts[0][1] == text


def _rc_lost(mode, **params):
    """Fly 5 s, then the receiver is lost (an injected loss) for 5 s of sim time."""
    v, fs = _Flying(mode, **params), FailsafeMonitor()
    _fly(v, fs, 5.0, None)
    lost_ns = v.sim_ns
    v.pilot.set_lost(True)
    _fly(v, fs, 5.0, None)
    return v, fs, lost_ns


def test_an_rc_loss_in_auto_returns_home_rc_fs_timeout_of_sim_time_after_the_loss():
    v, fs, lost_ns = _rc_lost(CopterMode.AUTO)
    assert fs.radio.active and v.mode.number == CopterMode.RTL
    (t, text), = v.texts
    assert text == "Radio Failsafe"
    assert 1.0 < (t - lost_ns) / 1e9 <= 1.0 + 2 * STEP_NS / 1e9     # RC_FS_TIMEOUT 1 s
    v.pilot.set_lost(False)
    _fly(v, fs, 1.0, None)
    assert not fs.radio.active and v.mode.number == CopterMode.RTL


def test_fs_options_let_auto_and_guided_go_on_through_an_rc_loss():
    v, _, _ = _rc_lost(CopterMode.AUTO, FS_OPTIONS=1)
    assert v.mode.number == CopterMode.AUTO and v.texts[0][1] == "Radio Failsafe - Continuing Auto"
    v, _, _ = _rc_lost(CopterMode.GUIDED, FS_OPTIONS=4)
    assert v.mode.number == CopterMode.GUIDED
    assert v.texts[0][1] == "Radio Failsafe - Continuing Guided Mode"
    v, _, _ = _rc_lost(CopterMode.GUIDED, FS_THR_ENABLE=3)       # no option: LAND
    assert v.mode.number == CopterMode.LAND


def test_a_ground_stations_sticks_going_quiet_fail_safe_only_in_a_pilot_flown_mode():
    """Pilot input from MANUAL_CONTROL that stops (not an injected loss): LOITER takes the
    radio failsafe; AUTO and GUIDED fly on, as ArduCopter SITL's simulated receiver takes
    over there when an override stops."""
    clock = [0.0]
    for mode, fails in ((CopterMode.LOITER, True), (CopterMode.AUTO, False),
                        (CopterMode.GUIDED, False)):
        v, fs = _Flying(mode), FailsafeMonitor()
        v.pilot = PilotInput(clock=lambda: clock[0])
        v.pilot.configure(RcConfig.from_params({p.name: p.default for p in PARAMS}.__getitem__))
        v.pilot.manual_control(0, 0, 500, 0)
        clock[0] += 5.0                              # no more input for 5 s of the link's time
        _fly(v, fs, 1.0, None)
        assert (v.mode.number != mode) == fails, (mode, v.texts)
        assert any(t == "Radio Failsafe" for _, t in v.texts) == fails
