"""The host tool ``bissmaster`` on a real serial port: ``--port`` names a pseudo-terminal, so
pyserial, the kernel's tty layer and :class:`bissmaster.host.link.SerialTransport` carry the
bytes, as on a board's USB-serial port. At the far end a thread passes them to and from the
bridge in software (tb/testkit/fake_board.py: ``MemoryBridge`` in front of the register-map
model), optionally damaging the answers. test_cli.py runs every command on the model through
a transport object; this file checks the path a user takes with ``--port``: positions read
over it, a board that does not answer, a garbled line, and a port that goes away in use.

Real time: each case takes well under a second (the link's timeouts at 115200 baud).
"""

import io
import os
import select
import sys
import threading

import pytest

from bissmaster.host import cli
from testkit.fake_board import FakeEncoder, biss_c_board

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="pseudo-terminals as serial ports: Linux")
#: docs/bench.md's exit codes (the test's own copy of those used here).
EXIT = {"ok": 0, "port": 3, "no board": 4, "link": 5}


class PtyBoard:
    """A pseudo-terminal whose far end answers as the board's UART bridge would: ``path`` is
    the port to give ``--port``. ``bridge``: a fake board (None: nothing answers).
    ``damage(answer bytes) -> bytes`` changes what goes back to the host."""

    def __init__(self, bridge=None, damage=None):
        self.bridge, self.damage = bridge, damage
        self.master, slave = os.openpty()
        self.path = os.ttyname(slave)
        os.close(slave)             # pyserial opens it by name; the master keeps the pair
        self.received = bytearray()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        while not self.stop.is_set():
            ready, _, _ = select.select([self.master], [], [], 0.01)
            if not ready:
                continue
            try:
                data = os.read(self.master, 4096)
            except OSError:         # no one has the port open (between two commands)
                continue
            self.received += data
            if self.bridge is None:
                continue
            self.bridge.write(data)
            answer = self.bridge.read(4096, 0)
            if answer and self.damage:
                answer = self.damage(answer)
            if answer:
                os.write(self.master, answer)

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.stop.set()
        self.thread.join()
        try:
            os.close(self.master)
        except OSError:
            pass


def run(argv):
    out, err = io.StringIO(), io.StringIO()
    code = cli.main(argv, stdout=out, stderr=err)
    return code, out.getvalue(), err.getvalue()


def test_read_and_counters_over_a_serial_port():
    bridge = biss_c_board(bits=26)
    bridge.model.encoders[0] = FakeEncoder(positions=lambda n: 5000 + 3 * n)
    with PtyBoard(bridge) as board:
        code, out, err = run(["read", "--port", board.path, "--count", "3", "--rate", "100"])
        assert code == EXIT["ok"], err
        rows = [line.split() for line in out.splitlines()[1:]]
        assert [(r[3], int(r[4])) for r in rows] == [("OK", 5000), ("OK", 5003), ("OK", 5006)]
        code, out, err = run(["counters", "--port", board.path])
        assert code == EXIT["ok"], err
        assert "no_ack" in out
    assert bridge.model.encoders[0].cycles == 3
    assert board.received[:1] == b"\xa5", "the requests crossed the port (SYNC first)"


def test_a_board_that_does_not_answer_on_a_serial_port():
    with PtyBoard(None) as board:
        code, _, err = run(["counters", "--port", board.path, "--retries", "1"])
    assert code == EXIT["no board"], err
    assert "does not answer" in err
    assert board.received, "the PING went out on the port"


def test_a_garbled_line_on_a_serial_port():
    """Every answer has a bit flipped on its way back: retried, then exit 5."""
    bridge = biss_c_board()
    damage = lambda answer: answer[:-1] + bytes([answer[-1] ^ 0x04])
    with PtyBoard(bridge, damage) as board:
        code, _, err = run(["counters", "--port", board.path, "--retries", "1"])
    assert code == EXIT["link"] and "garbled link" in err, (code, err)


def test_the_port_goes_away_while_in_use():
    """The USB-serial adapter unplugged mid-run (the pseudo-terminal's far end closed): exit 3,
    the port named."""
    bridge = biss_c_board()
    encoder = bridge.model.encoders[0] = FakeEncoder()
    board = PtyBoard(bridge)

    def unplug(answer):
        if encoder.cycles >= 2:
            board.stop.set()
            os.close(board.master)
            return b""
        return answer
    board.damage = unplug
    with board:
        code, out, err = run(["read", "--port", board.path, "--count", "100", "--rate", "100"])
    assert code == EXIT["port"], (code, err)
    assert board.path in err, err
