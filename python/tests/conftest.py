"""Shared test helpers."""

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def interrupted():
    """``interrupted(call, after, within=5)``: run ``energy_casimir.<call>``
    in a child Python from the repository root, send SIGINT ``after``
    seconds into the call, and assert that it ended with
    ``KeyboardInterrupt`` within ``within`` seconds of the signal instead of
    finishing (the call takes far longer when not interrupted; an interrupt
    honoured only when the call returns fails the time limit)."""

    def run(call: str, after: float, within: float = 5.0) -> None:
        # The child installs Python's own SIGINT handler: Python leaves
        # SIGINT alone when it starts with the signal ignored, as under GNU
        # time or in a background job, and the test would then fail for
        # its environment (measured: five failures under /usr/bin/time).
        code = ("import signal\nsignal.signal(signal.SIGINT, signal.default_int_handler)\n"
                f"import energy_casimir as ec\nprint('started', flush=True)\nec.{call}\nprint('finished', flush=True)\n")
        child = subprocess.Popen([sys.executable, "-c", code], cwd=REPO, stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True)
        try:
            assert child.stdout.readline().strip() == "started"
            time.sleep(after)
            child.send_signal(signal.SIGINT)
            sent = time.monotonic()
            out, err = child.communicate(timeout=120)
            assert time.monotonic() - sent < within, f"the interrupt took {time.monotonic() - sent:.1f} s"
            assert "finished" not in out
            assert "KeyboardInterrupt" in err, err
            assert child.returncode != 0
        finally:
            # a child that did not stop is not left running
            if child.poll() is None:
                child.kill()
                child.wait()

    return run
