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
    """``interrupted(call, after)``: run ``energy_casimir.<call>`` in a child
    Python from the repository root, send SIGINT ``after`` seconds into the
    call, and assert that it ended with ``KeyboardInterrupt`` instead of
    finishing (the call takes minutes when not interrupted)."""

    def run(call: str, after: float) -> None:
        code = f"import energy_casimir as ec\nprint('started', flush=True)\nec.{call}\nprint('finished', flush=True)\n"
        child = subprocess.Popen([sys.executable, "-c", code], cwd=REPO, stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True)
        assert child.stdout.readline().strip() == "started"
        time.sleep(after)
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=120)
        assert "finished" not in out
        assert "KeyboardInterrupt" in err, err
        assert child.returncode != 0

    return run
