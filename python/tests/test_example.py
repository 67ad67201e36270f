"""The notebook-style example runs as a script and reproduces the closed
form and the stopping time it prints."""

import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def test_rigid_body_example(tmp_path):
    pytest.importorskip("matplotlib")  # test.sh installs it
    run = subprocess.run(
        [sys.executable, str(REPO / "examples" / "rigid_body.py"), "--out", str(tmp_path), "--paths", "300"],
        capture_output=True, text=True, check=True, timeout=600,
    )
    text = run.stdout
    assert "rigid-body-major-axis: stable (exact), Sigma^2 = 27/100" in text
    t = float(re.search(r"T\(0\.1, 0\.001\) = ([0-9.]+)", text).group(1))
    assert t == pytest.approx(math.log(100) / 0.27, abs=1e-6)
    gap = float(re.search(r"closed form ([0-9.e+-]+)", text).group(1))
    assert gap < 1e-12
    for name in ("sigma2-vs-I2.png", "paper-figure-rigid-body.png"):
        assert (tmp_path / name).stat().st_size > 10_000
