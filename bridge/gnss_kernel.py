"""The GNSS epochs in C while nothing needs them in Python (bridge/src/gnss_model.h).

A GNSS epoch used to end the lockstep batch every 100 steps for Python's model
(lowrate.Gnss) to make its fix: a tenth of the one-process loop's time went there and to
the batch's end. The kernel's sensor stage makes the same fix, byte for byte, at the epoch's
step, and holds it to its release. Python keeps the model while its extras are in play:
- the first fix, released by Python so that its step ends a batch: the FC's supervisor
  looks up the declination at the first fix, after the batch that brought it
  (fc_sil/autoflight.py);
- a GNSS fault (bridge/faults/gnss.py makes its fixes);
- more fixes in flight than the kernel can hold (a latency of many epochs).
`place()` runs between steps when any of these may have changed (a step Python finishes;
the fault's switch, whoever makes it: Gnss.on_fault_change), and hands the model's state
(schedule, Gauss-Markov error, where the noise stream stands, the next sequence number)
over or back. The fixes are the same either way (tests/bridge/test_gnss_kernel.py).
"""

from __future__ import annotations

from silbridge.bridge import _step
from silbridge.bridge.lowrate import due_ns
from silbridge.shm.records import Kind

_U32 = 0xFFFFFFFF


class KernelGnss:
    """Where the simulator's GNSS epochs are made: `in_c` while the kernel makes them."""

    def __init__(self, gnss, kernel, seqs: list, dt_ns: int, ground_alt_m: float,
                 wanted: bool = True, moved=None):
        """seqs: the simulator's records-published counts by kind (the GNSS's is handed
        over and back); moved(): called after a fault's switch moved the model (the
        simulator's next slow step changes)."""
        self.gnss = gnss
        self.kernel = kernel
        self._seqs = seqs
        self._moved = moved
        self.in_c = False
        self._seq_given = 0          # the GNSS count when the kernel took over
        c = gnss.cfg
        rate = c.rate_hz
        # The most fixes ever held: those of the epochs within one latency and a step of
        # the newest, and the newest itself.
        most_held = int((gnss.latency_ns + dt_ns) * rate / 1e9) + 2
        self.able = wanted and hasattr(kernel, "gnss_take") and most_held <= _step.HELD_MAX
        if not self.able:
            return
        gnss.on_fault_change = self._fault_changed
        kernel.configure_gnss(
            rate_hz=rate, latency_ns=gnss.latency_ns,
            sigma_ned_m=(c.pos_sigma_h_m, c.pos_sigma_h_m, c.pos_sigma_v_m),
            tau_s=c.pos_tau_s, vel_sigma_m_s=c.vel_sigma_m_s,
            m_per_rad_lat=gnss.m_per_rad_lat, m_per_rad_lon=gnss.m_per_rad_lon,
            ground_alt_m=ground_alt_m, eph_cm=min(65535, int(round(c.pos_sigma_h_m * 100.0))),
            epv_cm=min(65535, int(round(c.pos_sigma_v_m * 100.0))), fix_type=c.fix_type,
            satellites=c.satellites)

    def place(self) -> bool:
        """Hand the model to the kernel or take it back, as the state asks; True when
        it moved (the simulator's next slow step changes then)."""
        want = self._kernel_may()
        if want == self.in_c:
            return False
        if want:
            self._to_kernel()
        else:
            self._from_kernel()
        return True

    def _fault_changed(self) -> None:
        """A GNSS fault switched (between steps): Python makes the fixes while it is on."""
        if self.place() and self._moved is not None:
            self._moved()

    def _kernel_may(self) -> bool:
        g = self.gnss
        return (self.able and g.fault is None and not g.pending
                and self._seqs[Kind.GNSS] > 0)

    def _to_kernel(self) -> None:
        g, kernel = self.gnss, self.kernel
        block, pos = g.noise.current_block()
        kernel.set_gnss_block(block, pos)
        seq = self._seqs[Kind.GNSS]
        self._seq_given = seq
        err = None if g.err_ned_m is None else tuple(g.err_ned_m)
        kernel.gnss_take(g.schedule.m, err, g.last_epoch_ns, seq & _U32)
        self.in_c = True

    def _from_kernel(self) -> None:
        g = self.gnss
        m, err, last_ns, pos, seq = self.kernel.gnss_give()
        g.schedule.m = m
        g.schedule.next_ns = due_ns(m, g.schedule.rate_hz)
        g.err_ned_m = None if err is None else list(err)
        g.last_epoch_ns = last_ns
        g.noise.seek(pos)
        self._seqs[Kind.GNSS] = self.records()
        self.in_c = False

    def records(self) -> int:
        """GNSS records made so far (held ones too)."""
        if not self.in_c:
            return self._seqs[Kind.GNSS]
        given = self._seq_given
        return given + ((self.kernel.gnss_seq - given) & _U32)

    def next_block(self) -> None:
        """The kernel used the last row of its noise block (F_GNSS_BLOCK_DONE)."""
        noise = self.gnss.noise
        block, _ = noise.current_block()
        noise.seek(block.shape[0])
        self.kernel.set_gnss_block(*noise.current_block())
