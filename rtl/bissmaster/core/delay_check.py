"""Line-delay plausibility: a frame whose round trip is not the settled one is doubtful."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out



class DelayCheck(wiring.Component):
    """Flags a frame whose measured round trip differs from the channel's settled one.

    A cable does not change length between two frames: once a channel has a settled round trip,
    a frame measured more than ``tolerance`` clocks away from it (``|delay - settled_delay| >
    tolerance``) is ``jump``, even with a passing CRC: it is most likely noise that fooled the
    Ack detection, and the master reports it with its own status, not as valid.

    Settling. Until it has settled the block flags nothing. The frames the master reports as
    otherwise good (``learn`` with ``clean``) form runs: the first frame of a run is its
    candidate, and each following clean frame within ``tolerance`` of the candidate counts; the
    ``settle_frames``-th frame of a run settles the channel at the candidate's delay
    (``settled`` rises, ``spread`` is 0). A clean frame outside the tolerance starts a new run
    from itself; a frame that is not clean (``learn`` with ``clean`` low) breaks the run, the
    next clean frame starts a new one.

    Settled. Each ``check`` latches ``jump`` for the frame. A clean frame that did not jump is
    accepted: ``spread`` keeps the largest ``|delay - settled_delay|`` of the accepted frames
    since the channel (re)settled. A frame that jumped while passing every other check (``learn``
    with ``clean`` while ``jump`` is set: its status is the delay's alone) counts toward
    re-settling at its own delay, in runs as above: ``settle_frames`` such frames in a row that
    agree within ``tolerance`` with the first of them move ``settled_delay`` to that first
    frame's delay (``resettled`` pulses, ``spread`` is 0). An accepted frame (back at the
    settled delay) or a frame that is not clean breaks such a run.

    So a cable whose length changes while powered (the round trip steps by more than
    ``tolerance``) costs exactly ``settle_frames`` frames, reported as jumps (never valid), on a
    clean line: the next frame is judged against the new delay and is valid again. A noisy line
    can only move the reference with ``settle_frames`` CRC-passing noise frames in a row that
    agree on one delay; alternating old and new delays never re-settle.

    Re-arming. ``rearm`` (a strobe), a reset, or ``enable`` low forgets everything: not settled,
    ``settled_delay`` and ``spread`` 0, no run, ``jump`` low (the clock after), and the next
    ``settle_frames`` clean frames settle the channel afresh. A user re-arms after a cable
    change if the ``settle_frames`` jump frames are not acceptable, and need not after power-up
    (reset). ``rearm`` wins over a ``check`` or ``learn`` in the same clock. While ``enable`` is
    low ``jump`` stays 0 and ``learn`` is ignored.

    A saturated ``delay`` (all ones: the sampler's "out of range") is never learned: it counts
    as a frame that is not clean.

    Timing. The difference to the settled delay and to the candidate, and the compares with
    ``tolerance``, are two pipeline stages (one subtracter each, registered, then the compare,
    registered), so no arithmetic sits in front of ``jump`` or the state. Hence ``check`` must
    come at least 2 clocks after ``delay`` and ``tolerance`` are final, and at least 2 clocks
    after the previous frame's ``learn`` (which moves the references); ``delay`` and
    ``tolerance`` must hold until the frame's ``learn``, which comes at least 1 clock after its
    ``check``. The master's ``check`` is where the decoder finds Start, at least one slot
    after the sampler's lock and at least two before the frame's end (CDS and one data bit), so
    ``jump`` is final when the verdict reads it at ``done``; its ``learn`` is at the frame's
    report. ``jump`` follows ``check`` by 1
    clock; ``settled``, ``settled_delay``, ``spread`` and ``resettled`` follow ``learn`` by 1
    clock.

    Parameters
    ----------
    delay_width : int
        Bits of the measured round trip (the sampler's ``delay``).
    settle_frames : int
        Frames in a run that settle (or re-settle) the channel: 2..15.

    Attributes
    ----------
    enable : In(1)
        The check is on; low forgets everything.
    tolerance : In(tolerance_width)
        Clocks: the largest ``|delay - settled_delay|`` that is not a jump, and the largest
        distance to a run's candidate that agrees with it.
    rearm : In(1)
        Strobe: forget the settled delay.
    delay : In(delay_width)
        The cycle's measured round trip.
    check : In(1)
        Strobe: latch the verdict for this frame into ``jump``.
    learn : In(1)
        Strobe, at most once per frame, after its ``check``: update the state from the frame.
    clean : In(1)
        Valid with ``learn``: the frame passed every other check (CRCs and the rest).
    jump : Out(1)
        The checked frame's round trip is more than ``tolerance`` from ``settled_delay``; 0 if
        the block was not enabled or not settled. Held until the next ``check``.
    settled : Out(1)
    settled_delay : Out(delay_width)
        The reference round trip (0 while not settled).
    spread : Out(spread_width)
        The largest ``|delay - settled_delay|`` of a frame accepted since the channel settled.
    resettled : Out(1)
        Strobe: ``settled_delay`` moved to a new delay (a re-settle; the first settling is seen
        on ``settled``).
    """

    def __init__(self, delay_width, settle_frames=4, *, tolerance_width=4, spread_width=4):
        if not isinstance(delay_width, int) or delay_width < 1:
            raise ValueError(f"delay_width must be a positive integer, not {delay_width!r}")
        if not isinstance(settle_frames, int) or not 2 <= settle_frames <= 15:
            raise ValueError(f"settle_frames must be an integer from 2 to 15, "
                             f"not {settle_frames!r}")
        for name, value in (("tolerance_width", tolerance_width), ("spread_width", spread_width)):
            if not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} must be a positive integer, not {value!r}")
        self._delay_width = delay_width
        self._settle_frames = settle_frames
        self._spread_width = spread_width
        super().__init__({
            "enable": In(1),
            "tolerance": In(tolerance_width),
            "rearm": In(1),
            "delay": In(delay_width),
            "check": In(1),
            "learn": In(1),
            "clean": In(1),
            "jump": Out(1),
            "settled": Out(1),
            "settled_delay": Out(delay_width),
            "spread": Out(spread_width),
            "resettled": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        width = self._delay_width
        frames = self._settle_frames

        cand = Signal(width)                    # the current run's first delay
        count = Signal(range(frames))           # frames in the run (0: no run)

        # Stage 1: one subtracter per reference, a sign bit on top (delay - ref, width + 1 bits).
        diff_ref = Signal(width + 1)
        diff_cand = Signal(width + 1)
        tolerance = Signal(len(self.tolerance))
        saturated = Signal()
        m.d.sync += [
            diff_ref.eq(self.delay - self.settled_delay),
            diff_cand.eq(self.delay - cand),
            tolerance.eq(self.tolerance),
            saturated.eq(self.delay == (1 << width) - 1),
        ]

        # Stage 2: |d| > tolerance without a second adder. For d < 0, ~d (inverters only) is
        # |d| - 1, so |d| > tol is ~d >= tol; for d >= 0 it is d > tol.
        def sign_and_low(d):
            neg = d[width]
            low = Mux(neg, ~d[:width], d[:width])         # |d| - neg, fits in width bits
            return neg, low

        def beyond(d):
            neg, low = sign_and_low(d)
            return (low > tolerance) | (neg & (low == tolerance))

        far_ref = Signal()
        near_cand = Signal()
        # |delay - settled_delay| for ``spread``, saturating at its all-ones value.
        sw = self._spread_width
        top = (1 << sw) - 1
        magnitude = Signal(sw)
        neg, low = sign_and_low(diff_ref)
        low_sum = Signal(sw + 1)                # an sw-bit increment: |d| when |d| <= top
        m.d.comb += low_sum.eq(low[:sw] + neg)
        high = low[sw:].any() if width > sw else C(0)
        m.d.sync += [
            far_ref.eq(beyond(diff_ref)),
            near_cand.eq(~beyond(diff_cand)),
            magnitude.eq(Mux(high | low_sum[sw], top, low_sum[:sw])),
        ]

        m.d.sync += self.resettled.eq(0)

        with m.If(self.check):
            m.d.sync += self.jump.eq(self.settled & far_ref)

        # A saturated delay is out of range: never a candidate, never accepted.
        clean = self.clean & ~saturated
        accepted = self.settled & ~self.jump
        with m.If(self.learn):
            with m.If(~clean | accepted):
                # A frame that is not clean breaks the run; so does one at the settled delay
                # (an alternation old / new must never re-settle).
                m.d.sync += count.eq(0)
                with m.If(clean & (magnitude > self.spread)):
                    m.d.sync += self.spread.eq(magnitude)
            with m.Elif((count == 0) | ~near_cand):
                # A new run from this frame (not settled, or settled and jumped).
                m.d.sync += [cand.eq(self.delay), count.eq(1)]
            with m.Elif(count == frames - 1):
                m.d.sync += [
                    self.settled_delay.eq(cand),
                    self.settled.eq(1),
                    self.spread.eq(0),
                    count.eq(0),
                    self.resettled.eq(self.settled),
                ]
            with m.Else():
                m.d.sync += count.eq(count + 1)

        # Forgetting wins over everything (cand needs no clearing: count 0 means no run).
        with m.If(self.rearm | ~self.enable):
            m.d.sync += [
                self.settled.eq(0),
                self.settled_delay.eq(0),
                self.spread.eq(0),
                count.eq(0),
                self.jump.eq(0),
                self.resettled.eq(0),
            ]

        return m
