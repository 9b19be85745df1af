"""The link side of PX4's simulator contract: listen, freewheel, then lockstep or real time.

    server = Px4HilServer(physics, ("127.0.0.1", 4560 + N))      # or a serial channel
    result = server.serve(duration_s, realtime=False, stop=...)

PX4 connects (TCP; `simulator_mavlink start -c PORT`). Until its first HIL_ACTUATOR_CONTROLS
the server freewheels: one PX4 step with the motors stopped per FREEWHEEL_WALL_S of wall time,
because PX4 cannot answer before its estimator and logger run, and they need sim time to move.
Real time freewheels a PX4 SITL (one that connects to the listener) at that pace too: fed at
the step period (4 ms), PX4 v1.15's EKF2 often started with a vertical velocity at rest and
stood ~1 m off the ground ever after (tools/autopilots/px4/rest_height.py): on an idle 2-core
VM 7 of 24 such boots were good, and 16 of 16 fed at FREEWHEEL_WALL_S. A board on a serial
line (a channel given) runs on its own clock and is fed at the step period from the start.
Then:
- lockstep (default): one step per reply that answers the last step sent (physics.py
  tells); a reply that never comes within `stall_s` wall seconds makes the server step anyway
  (counted as unanswered: reported, never silent), and `idle_timeout_s` without any message
  from PX4 ends the run with an error.
- real time: a step every 1/step_hz of wall time with the newest motors, whatever PX4 answered
  (the way a person watches PX4 fly our physics in QGroundControl).
PX4's SET_MESSAGE_INTERVAL for HIL_STATE_QUATERNION sets the truth interval.

Start-up check (after STARTUP_CHECK_S of sim time past the first reply): PX4's own rate is
the reference for a foreign autopilot, so the check is on counters, not on our FC's 400 Hz:
no CRC or framing errors on the link, PX4's lockstep flag set in lockstep, every step
answered (lockstep) or replies at >= 90 % of the step rate (real time). In real time the
rate is judged over successive STARTUP_CHECK_S windows until one passes or STARTUP_CHECK_MAX_S
is reached: PX4 booting on a busy machine can answer slowly for a second or two, and that is not
the misconfigured rate the check exists to catch (a PX4 at the wrong rate never passes a window).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

from silbridge.mavlink.hil.hil_channel import HilListener
from silbridge.mavlink.hil.hil_errors import HilPeerLost
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.bridge.autopilots.px4.hil_messages import (
    CMD_SET_MESSAGE_INTERVAL,
    MSG_HIL_ACTUATOR_CONTROLS,
    Px4Controls,
)

from silbridge.bridge.link_spin import spin_poll
from silbridge.bridge.errors import PeerLost, StartupCheckFailed
from silbridge.bridge.serve_loop import ServeResult, ended_by, stop_asked
from silbridge.shm.records import NS_PER_S as _NS

FREEWHEEL_WALL_S = 0.001
STARTUP_CHECK_S = 2.0
STARTUP_CHECK_MAX_S = 10.0
MSG_COMMAND_LONG = 76


@dataclass
class Px4RunResult(ServeResult):
    startup_check: dict = field(default_factory=dict)


class Px4HilServer:
    def __init__(self, physics, address=("127.0.0.1", 4560), *, channel=None):
        """address: where to listen for PX4 (TCP); channel: an open link instead (serial)."""
        self.physics = physics
        self.listener = None if channel is not None else HilListener(address[0], address[1],
                                                                      False)
        self.address = address if self.listener is None else self.listener.addr
        self.channel = channel
        self.check: dict = {}
        # (sim s past the first reply, replies then): the start of the window the rate is judged on
        self._rate_window = (0.0, 0)

    def close(self) -> None:
        if self.channel is not None:
            self.channel.close()
        if self.listener is not None:
            self.listener.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- the loop -----------------------------------------------------------------------------
    def _accept(self, timeout_s: float, stop) -> None:
        end = time.monotonic() + timeout_s
        codec = self.physics.encoder.codec
        while self.channel is None:
            self.channel = self.listener.accept(codec, 0.1)
            if stop_asked(stop):
                return
            if self.channel is None and time.monotonic() > end:
                raise PeerLost(f"PX4 did not connect to {self.address[0]}:{self.address[1]} "
                               f"within {timeout_s:g} s: start it with PX4_SYS_AUTOSTART=10016 "
                               f"`px4 -i N` (it connects to 4560 + N), or check its console")

    def _handle(self, msgs, rx_ns: int) -> int:
        """Messages from PX4 -> how many replies answer the last step."""
        phys = self.physics
        answers = 0
        for m in msgs:
            mid = m.get_msgId()
            if mid == MSG_HIL_ACTUATOR_CONTROLS:
                if phys.on_controls(m, rx_ns):
                    answers += 1
            elif mid == MSG_COMMAND_LONG and m.command == CMD_SET_MESSAGE_INTERVAL:
                phys.encoder.set_interval(m.param1, m.param2)
        return answers

    def _send_step(self, **kw) -> None:
        frames: list = []
        self.physics.step(frames, **kw)
        try:
            self.channel.send(frames)
            self.physics.sent(time.monotonic_ns())
        except HilPeerLost as e:
            raise PeerLost(f"PX4 went away: {e}") from None

    def serve(self, duration_s: float, *, realtime: bool = False, connect_timeout_s: float = 60.0,
              stall_s: float = 2.0, idle_timeout_s: float = 10.0, stop=None,
              spin_us: float = 0.0) -> Px4RunResult:
        """spin_us: in lockstep, poll for PX4's reply without sleeping for up to this long
        before sleeping in select() (bridge/link_spin.py says when that pays; 0 sleeps at once)."""
        phys = self.physics
        spin_ns = int(spin_us * 1000)
        t0 = time.monotonic()
        self._accept(connect_timeout_s, stop)
        if self.channel is not None:     # PX4's reply, once per step: no pymavlink object
            self.channel.shortcut(mav.MAVLink_hil_actuator_controls_message, Px4Controls.of_wire)
        end_ns = int(round(duration_s * _NS))
        step_wall = 1.0 / phys.step_hz
        stopped_by = "duration"
        ch = self.channel
        last_rx = time.monotonic()
        pending = 0                  # answers not yet stepped on (lockstep)
        next_wall = time.monotonic()
        # the freewheel's pace: a SITL boots on sim time, a board on its own clock (docstring)
        boot_wall = step_wall if realtime and self.listener is None else FREEWHEEL_WALL_S
        while phys.sim.sim_ns < end_ns and ch is not None:
            now = time.monotonic()
            booting = phys.first_reply_us is None
            if booting or realtime:
                wait = max(0.0, min(next_wall - now, boot_wall if booting else step_wall))
            else:
                wait = 0.0 if pending else min(stall_s, 0.05)
            if wait > 0 and spin_ns and not realtime and not booting:
                msgs = spin_poll(lambda: ch.receive(0) or None, spin_ns) or ch.receive(wait)
            else:
                msgs = ch.receive(wait)
            rx_ns = time.monotonic_ns()
            if msgs:
                last_rx = time.monotonic()
                pending += self._handle(msgs, rx_ns)
            if ch.eof:
                if stop_asked(stop):
                    stopped_by = "stop"
                    break
                raise PeerLost(f"PX4 closed the simulator link at sim time "
                               f"{phys.sim.sim_ns / _NS:.3f} s ({ch.error}): did it crash or "
                               "was it stopped? Check its console output")
            now = time.monotonic()
            if now - last_rx > idle_timeout_s:
                raise PeerLost(f"PX4 sent nothing for {idle_timeout_s:g} s at sim time "
                               f"{phys.sim.sim_ns / _NS:.3f} s: is it hung?")
            if phys.first_reply_us is None:          # freewheel until PX4 answers
                if now >= next_wall:
                    next_wall = now + boot_wall
                    self._send_step(freewheel=True)
            elif realtime:
                if now >= next_wall:
                    next_wall = max(next_wall + step_wall, now - 4 * step_wall)
                    self._send_step(answered=pending > 0)
                    pending = 0
            elif pending:
                pending -= 1
                self._send_step()
                next_wall = now + stall_s
            elif now >= next_wall:                   # the answer never came: step anyway
                self._send_step(answered=False)
                next_wall = now + stall_s
            self._startup_check(realtime)
            end = ended_by(phys.sim, stop)
            if end:
                stopped_by = end
                break
        stats = phys.stats()
        if ch is not None:
            stats.update(ch.rx.as_dict(), tx_frames=ch.tx_frames, tx_bytes=ch.tx_bytes)
        return Px4RunResult.of(phys.sim, t0, stats, stopped_by, startup_check=self.check)

    def _startup_check(self, realtime: bool) -> None:
        phys = self.physics
        if self.check or phys.first_reply_us is None:
            return
        since_s = (phys.last_sent_us - phys.first_reply_us) / 1e6
        win_s, win_replies = self._rate_window
        if since_s - win_s < STARTUP_CHECK_S:
            return
        rate = (phys.replies - win_replies) / max(since_s - win_s, 1e-9)
        slow = realtime and rate < 0.9 * phys.step_hz
        if slow and since_s < STARTUP_CHECK_MAX_S:
            self._rate_window = (since_s, phys.replies)       # judge the next window
            return
        rx = self.channel.rx
        steps = phys.steps - phys.freewheel_steps
        self.check = {"after_sim_s": since_s, "steps": steps, "replies": phys.replies,
                      "reply_hz": rate, "unanswered": phys.unanswered,
                      "bad_crc": rx.rx_bad_crc, "malformed": rx.rx_malformed,
                      "px4_lockstep_flag": phys.lockstep_flag, "passed": True}
        problems = []
        if rx.rx_bad_crc or rx.rx_malformed:
            problems.append(f"{rx.rx_bad_crc} bad CRC, {rx.rx_malformed} malformed frames "
                            "from PX4")
        if not realtime:
            if not phys.lockstep_flag:
                problems.append("PX4's HIL_ACTUATOR_CONTROLS lack the lockstep flag: a PX4 "
                                "built without lockstep needs --realtime")
            if phys.unanswered:
                problems.append(f"{phys.unanswered} of {steps} steps unanswered")
        elif slow:
            problems.append(f"PX4 answered at {rate:.0f} Hz over the last "
                            f"{since_s - win_s:.1f} s, want >= 90 % of its {phys.step_hz} Hz "
                            f"step rate in some {STARTUP_CHECK_S:g} s window of the first "
                            f"{STARTUP_CHECK_MAX_S:g} s")
        if problems:
            self.check["passed"] = False
            self.check["problems"] = problems
            raise StartupCheckFailed("start-up check failed with PX4: " + "; ".join(problems))

