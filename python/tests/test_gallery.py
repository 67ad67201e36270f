"""The gallery (examples/*.py, jupytext percent notebooks) runs as scripts:
each asserts its published or derived numbers itself and writes its
figures; here the printed numbers are checked again against their sources,
and each file is read as a notebook by jupytext."""

import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
GALLERY = ["rigid_body.py", "shear_flows.py", "lagrange_top_map.py", "zeitlin_quflow.py"]


def run(name, tmp_path, *extra):
    pytest.importorskip("matplotlib")  # test.sh installs it
    done = subprocess.run([sys.executable, str(REPO / "examples" / name), "--out", str(tmp_path), *extra],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


def test_rigid_body(tmp_path):
    text = run("rigid_body.py", tmp_path, "--paths", "300")
    assert "rigid-body-major-axis: stable (exact), Sigma^2 = 27/100" in text
    t = float(re.search(r"T\(0\.1, 0\.001\) = ([0-9.]+)", text).group(1))
    assert t == pytest.approx(math.log(100) / 0.27, abs=1e-6)  # T = ln(eps/delta)/Sigma^2
    gap = float(re.search(r"closed form ([0-9.e+-]+)", text).group(1))
    assert gap < 1e-12
    for name in ("sigma2-vs-I2.png", "paper-figure-rigid-body.png"):
        assert (tmp_path / name).stat().st_size > 10_000


def test_shear_flows(tmp_path):
    text = run("shear_flows.py", tmp_path)
    # Michalke (1964): growth rate 0.1897 at k = 0.4446 (four digits).
    rate = float(re.search(r"tanh y, k = 0\.4446: linearly_unstable, growth rate ([0-9.]+)", text).group(1))
    assert abs(rate - 0.1897) < 5e-5
    # The Bickley jet's sinuous band ends at k = 2; Kolmogorov flow's at k = 1.
    assert "sech^2 y, k = 1.9: linearly_unstable" in text and "sech^2 y, k = 2.01: stable" in text
    assert "sin y, k = 0.99: linearly_unstable" in text and "sin y, k = 1.01: stable" in text
    assert (tmp_path / "shear-flows.png").stat().st_size > 10_000


def test_lagrange_top_map(tmp_path):
    text = run("lagrange_top_map.py", tmp_path)
    assert "lagrange-top-map: partly_stable" in text
    # int_{1/2}^{3/2} (2 sqrt(mgl) - 1) d mgl / 2, by hand: 0.489043.
    assert "area below the curve: 48.9043% of the box" in text
    assert (tmp_path / "lagrange-top-map.png").stat().st_size > 10_000


def test_zeitlin_quflow(tmp_path):
    pytest.importorskip("h5py")  # the wheel's quflow extra
    text = run("zeitlin_quflow.py", tmp_path)
    assert text.count(": stable (verified_float)") == 5
    # a_1 = sqrt(3) (1/3 + 0.3/5) and a_3 = sqrt(7) 0.3 (2/35) for z + 0.3 z^3
    # (z = P_1, z^3 = (2 P_3 + 3 P_1)/5, and 1/2 int P_l^2 = 1/(2l+1)).
    a = re.search(r"a_l: \{1: ([0-9.e-]+), 2: [-0-9.e]+, 3: ([0-9.e-]+)", text)
    assert float(a.group(1)) == pytest.approx(math.sqrt(3) * (1 / 3 + 0.3 / 5), abs=1e-12)
    assert float(a.group(2)) == pytest.approx(math.sqrt(7) * 0.3 * 2 / 35, abs=1e-12)
    for n in (16, 32, 64, 128, 256):
        assert (tmp_path / f"zonal-n{n}.hdf5").exists()
    assert (tmp_path / "zeitlin-convergence.png").stat().st_size > 10_000
    assert "block m = 1: Sigma^2 = " in text
    assert (tmp_path / "zeitlin-monte-carlo.png").stat().st_size > 10_000


@pytest.mark.parametrize("name", GALLERY)
def test_each_file_is_a_notebook(name):
    jupytext = pytest.importorskip("jupytext")  # test.sh installs it
    notebook = jupytext.read(REPO / "examples" / name)
    kinds = [cell.cell_type for cell in notebook.cells]
    assert kinds.count("markdown") >= 2 and kinds.count("code") >= 3, kinds
    assert notebook.cells[0].cell_type == "markdown" and notebook.cells[0].source.startswith("# ")
