"""quflow files in and out (energy_casimir.quflow).

The expected values come from outside the module: a file quflow itself
wrote (``python/tests/data/quflow-tilted-n16.hdf5``: quflow 0.1.0's
``quflow.save`` of the matrices in ``fixtures/zeitlin/quflow-tilted-n16-*.npy``,
the noise's stream function at qtime 0, then the state at qtime 2.5), the
committed certificates of the same states, and spherical-harmonic
coefficients computed here by quadrature with scipy's ``sph_harm_y``.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest

import energy_casimir as ec

h5py = pytest.importorskip("h5py")
special = pytest.importorskip("scipy.special")
from energy_casimir import quflow  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
QUFLOW_FILE = Path(__file__).resolve().parent / "data" / "quflow-tilted-n16.hdf5"


def certificate(name):
    return json.loads((REPO / "fixtures" / "zeitlin" / f"{name}.cert.json").read_text())


def shr_by_quadrature(f, N, lmax):
    """quflow's real coefficients of f(x, y, z) on the unit sphere, by
    quadrature: complex c_lm = (1/4 pi) int f conj(sqrt(4 pi) Y_lm) (scipy's
    orthonormal Y_lm with the Condon-Shortley phase), then quflow's
    shc2shr: r_l0 = Re c_l0, r_{l,m} = sqrt(2) (-1)^m Re c_lm,
    r_{l,-m} = sqrt(2) (-1)^m Im c_lm. Gauss-Legendre in z (24 nodes) and 48
    equal steps in phi are exact for the polynomials of degree 6 used here."""
    z, wz = np.polynomial.legendre.leggauss(24)
    phi = 2 * np.pi * np.arange(48) / 48
    Z, PHI = np.meshgrid(z, phi, indexing="ij")
    THETA = np.arccos(Z)
    X, Y = np.sqrt(1 - Z**2) * np.cos(PHI), np.sqrt(1 - Z**2) * np.sin(PHI)
    weights = wz[:, None] * (2 * np.pi / 48) * np.ones_like(PHI)
    values = f(X, Y, Z)
    omega = np.zeros(N * N)
    for l in range(lmax + 1):
        for m in range(0, l + 1):
            Ylm = special.sph_harm_y(l, m, THETA, PHI)
            c = np.sum(weights * values * np.conj(np.sqrt(4 * np.pi) * Ylm)) / (4 * np.pi)
            if m == 0:
                omega[l * l + l] = c.real
            else:
                s = math.sqrt(2) * (-1) ** m
                omega[l * l + l + m] = s * c.real
                omega[l * l + l - m] = s * c.imag
    return omega


def test_a_file_quflow_wrote_certifies_as_the_matrices_it_was_written_from():
    state = quflow.read(QUFLOW_FILE)  # the last output
    assert (state.N, state.step, state.qtime) == (16, 1, 2.5)
    # quflow's time = qtime * hbar, hbar = 2 / sqrt(N^2 - 1).
    assert state.time == pytest.approx(2.5 * 2 / math.sqrt(255), rel=1e-15)
    noise = quflow.read(QUFLOW_FILE, step=0).omega
    spec = quflow.zeitlin_spec(state, noise=[noise], stopping={"epsilon": 0.1, "delta": 0.001},
                               settings={"casimir_momentum": False})
    assert "t = " in spec["description"] and "qtime 2.5" in spec["description"]
    cert = ec.certify(spec)
    committed = certificate("quflow-tilted-n16")  # from quflow's .npy matrices
    assert (cert.verdict, cert.level) == ("stable", "verified_float")
    assert cert.sigma2 == pytest.approx(committed["sigma2"], rel=1e-9)
    assert cert.sigma2_upper == pytest.approx(committed["sigma2_upper"], rel=1e-9)
    # The axis pins the signs of the m < 0 coefficients (Sigma^2 does not
    # see a mirror image).
    assert cert["frame"]["axis"] == pytest.approx(committed["frame"]["axis"], abs=1e-12)
    assert ec.check(cert).verdict == "stable"


def test_a_zonal_state_from_scipy_harmonics_certifies_as_its_expression(tmp_path):
    # omega = z + 0.3 z^3, noise 0.1 z^2 at N = 32: the state of
    # fixtures/zeitlin/energy-casimir-n32.json, written as quflow would.
    N = 32
    omega = shr_by_quadrature(lambda x, y, z: z + 0.3 * z**3, N, 5)
    xi = shr_by_quadrature(lambda x, y, z: 0.1 * z**2, N, 5)
    # Closed form of the l = 1 coefficient: (1/2) int (z + 0.3 z^3) sqrt(3) z dz
    # = sqrt(3) (1/3 + 0.3/5).
    assert omega[2] == pytest.approx(math.sqrt(3) * (1 / 3 + 0.3 / 5), rel=1e-13)
    omega[np.abs(omega) < 1e-14] = 0.0
    xi[np.abs(xi) < 1e-14] = 0.0
    path = tmp_path / "zonal.hdf5"
    quflow.write(path, np.vstack([xi, omega]), time=[0.0, 1.0])
    spec = quflow.zeitlin_spec(path, noise=[quflow.read(path, step=0).omega],
                               stopping={"epsilon": 0.1, "delta": 0.001}, settings={"casimir_momentum": False})
    cert = ec.certify(spec)
    committed = certificate("energy-casimir-n32")
    assert cert.verdict == "stable"
    assert cert.sigma2 == pytest.approx(committed["sigma2"], rel=1e-8)


def test_a_tilted_state_from_scipy_harmonics_certifies_as_the_zonal_one(tmp_path):
    # The same profile about the axis n: the engine finds the axis and its
    # Sigma^2 is the zonal state's (rotation invariance of the model).
    N = 32
    n = np.array([0.48, -0.6, 0.64])
    omega = shr_by_quadrature(lambda x, y, z: (n[0] * x + n[1] * y + n[2] * z) + 0.3 * (n[0] * x + n[1] * y + n[2] * z) ** 3, N, 5)
    xi = shr_by_quadrature(lambda x, y, z: 0.1 * (n[0] * x + n[1] * y + n[2] * z) ** 2, N, 5)
    assert np.count_nonzero(np.abs(omega) > 1e-3) > 3  # not zonal in the file's frame
    omega[np.abs(omega) < 1e-14] = 0.0
    xi[np.abs(xi) < 1e-14] = 0.0
    path = tmp_path / "tilted.hdf5"
    quflow.write(path, omega, qtime=[0.0])
    spec = quflow.zeitlin_spec(path, noise=[xi], settings={"casimir_momentum": False})
    cert = ec.certify(spec)
    assert cert.verdict == "stable"
    assert cert["frame"]["kind"] == "rotated"
    assert cert.sigma2 == pytest.approx(certificate("energy-casimir-n32")["sigma2"], rel=1e-8)
    # The axis, derived: these coefficients are of quflow's function picture
    # (shc2shr), which is its matrix frame mirrored in y, so the state's l = 1
    # part (omega_11, omega_1-1, omega_10) points along (0.48, 0.6, 0.64);
    # certificates report axes in quflow's matrix frame, as that direction
    # (largest component positive; docs/python.md).
    assert (omega[3], omega[1], omega[2]) == pytest.approx(tuple(0.6812733176437584 * np.array([0.48, 0.6, 0.64])), rel=1e-12)
    assert cert["frame"]["axis"] == pytest.approx([0.48, 0.6, 0.64], abs=1e-12)


def test_written_files_have_quflows_layout_and_read_back(tmp_path):
    N = 5
    rng = np.random.default_rng(7)
    rows = rng.standard_normal((3, N * N))
    path = tmp_path / "out.hdf5"
    quflow.write(path, rows[:2], time=[0.0, 0.75])
    quflow.write(path, rows[2])  # no time: qtime goes on in steps of 1, as quflow.save
    quflow.write(path, [[2, -1, 0.5], [4, 4, -1.25]], qtime=[9.0])  # harmonics
    hb = 2 / math.sqrt(N * N - 1)
    with h5py.File(path, "r") as f, h5py.File(QUFLOW_FILE, "r") as theirs:
        for name in ("state", "time", "qtime"):
            assert f[name].dtype == theirs[name].dtype
            assert f[name].maxshape[0] is None
        assert f["state"].chunks == (1, N * N) and theirs["state"].chunks == (1, 256)
        assert f["state"].attrs["qtype"] == theirs["state"].attrs["qtype"] == "shr"
        assert f.attrs["N"] == N and type(f.attrs["N"]) is type(theirs.attrs["N"])
        assert set(f.attrs) >= {"N", "version", "created"}
        assert f["state"].shape == (4, N * N)
        np.testing.assert_allclose(f["qtime"][:], [0.0, 0.75 / hb, 0.75 / hb + 1, 9.0], rtol=1e-15)
        np.testing.assert_allclose(f["time"][:], f["qtime"][:] * hb, rtol=1e-15)
    for step in range(3):
        back = quflow.read(path, step)
        np.testing.assert_array_equal(back.omega, rows[step])
    last = quflow.read(path)
    assert last.step == 3 and last.qtime == 9.0
    assert quflow.harmonics(last.omega) == [[2, -1, 0.5], [4, 4, -1.25]]
    np.testing.assert_array_equal(quflow.omega_from_harmonics(quflow.harmonics(rows[0]), N)[1:], rows[0][1:])


def test_shc_rows_are_read_as_quflows_real_coefficients(tmp_path):
    # quflow 0.1.0's own shr2shc of omega = (-1, -11/12, ..., 1) rounded to
    # 3 decimals, N = 5 (printed by quflow, not computed here).
    omega = np.round(np.linspace(-1, 1, 25), 3)
    re = [-1.0, -0.5303300858899106, -0.833, 0.5303300858899106, -0.23546655813512032, -0.2948635277547903, -0.5,
          0.2948635277547903, -0.23546655813512032, 0.17677669529663687, 0.11808683245815343, 0.058689862838483445,
          0.0, -0.058689862838483445, 0.11808683245815343, -0.17677669529663687, 0.7071067811865475, 0.648416918348064,
          0.589019948728394, 0.5303300858899106, 0.667, -0.5303300858899106, 0.589019948728394, -0.648416918348064,
          0.7071067811865475]
    im = [0.0, 0.648416918348064, 0.0, 0.648416918348064, 0.47164022305142717, 0.41224325343175716, 0.0,
          0.41224325343175716, -0.47164022305142717, 0.17677669529663687, 0.11808683245815343, 0.058689862838483445,
          0.0, 0.058689862838483445, -0.11808683245815343, 0.17677669529663687, -0.23546655813512032,
          -0.2948635277547903, -0.35355339059327373, -0.41224325343175716, 0.0, -0.41224325343175716,
          0.35355339059327373, -0.2948635277547903, 0.23546655813512032]
    path = tmp_path / "shc.hdf5"
    with h5py.File(path, "w") as f:
        f.attrs["N"] = np.int64(5)
        s = f.create_dataset("state", data=(np.array(re) + 1j * np.array(im))[None, :])
        s.attrs["qtype"] = "shc"
    np.testing.assert_allclose(quflow.read(path).omega, omega, rtol=0, atol=1e-15)
    # Complex values under qtype "shr" (or real ones under "shc") are refused.
    bad = tmp_path / "bad.hdf5"
    with h5py.File(bad, "w") as f:
        f.create_dataset("state", data=np.ones((1, 16), dtype=complex)).attrs["qtype"] = "shr"
    with pytest.raises(ValueError, match=r"qtype 'shr' but complex values"):
        quflow.read(bad)


def test_a_refused_write_leaves_the_file_as_it_was(tmp_path):
    # Appending to complex rows, to a QuSimulation file, or with bad times
    # changes nothing; a refused first write creates no file.
    shc = tmp_path / "shc.hdf5"
    with h5py.File(shc, "w") as f:
        f.attrs["N"] = np.int64(4)
        f.create_dataset("state", data=np.ones((1, 16), dtype=complex), maxshape=(None, 16), chunks=(1, 16)).attrs["qtype"] = "shc"
        f.create_dataset("qtime", data=[0.0], maxshape=(None,))
        f.create_dataset("time", data=[0.0], maxshape=(None,))
    sim = tmp_path / "sim.hdf5"
    with h5py.File(sim, "w") as f:
        f.attrs["N"] = np.int64(4)
        f.create_dataset("mat", data=np.zeros((1, 4, 4), dtype=complex))
        f.create_dataset("time", data=[0.0])
    ours = tmp_path / "ours.hdf5"
    quflow.write(ours, np.ones(16), time=[0.0])
    before = {p: p.read_bytes() for p in (shc, sim, ours)}
    with pytest.raises(ValueError, match=r"only real float64 rows"):
        quflow.write(shc, np.ones(16))
    with pytest.raises(ValueError, match=r"has mat, time but no `state`"):
        quflow.write(sim, np.ones(16))
    with pytest.raises(ValueError, match=r"time: a value .* is not finite"):
        quflow.write(ours, np.ones(16), time=[np.inf])
    with pytest.raises(ValueError, match=r"time: a value .* is not finite"):
        quflow.write(ours, np.ones(16), time=[1e308])  # qtime = time / hbar overflows
    assert {p: p.read_bytes() for p in (shc, sim, ours)} == before
    fresh = tmp_path / "fresh.hdf5"
    with pytest.raises(ValueError, match=r"time: 2 values for 1 states"):
        quflow.write(fresh, np.zeros(16), time=[0.0, 1.0])
    with pytest.raises(ValueError, match=r"harmonics need the file's N"):
        quflow.write(fresh, [[1, 0, 1.0]])
    assert not fresh.exists()
    # Times are stored as given.
    quflow.write(ours, np.ones(16), time=[7.3])
    with h5py.File(ours, "r") as f:
        assert f["time"][-1] == 7.3


def test_files_of_quflows_old_scaling_are_refused(tmp_path):
    # Before December 2023 quflow wrote time = qtime sqrt(16 pi) / N^(3/2).
    N = 4
    path = tmp_path / "old.hdf5"
    with h5py.File(path, "w") as f:
        f.attrs["N"] = np.int64(N)
        f.create_dataset("state", data=np.ones((1, N * N))).attrs["qtype"] = "shr"
        f.create_dataset("qtime", data=[2.0])
        f.create_dataset("time", data=[2.0 * math.sqrt(16 * math.pi) / N**1.5])
    with pytest.raises(ValueError, match=r"is not qtime \* hbar .* before December 2023"):
        quflow.read(path)


def test_bad_files_and_arguments_name_what_is_wrong(tmp_path):
    with pytest.raises(ValueError, match=r"step: 2 is out of range for 2 outputs"):
        quflow.read(QUFLOW_FILE, step=2)
    with pytest.raises(ValueError, match=r"step: expected an integer"):
        quflow.read(QUFLOW_FILE, step=1.5)
    sim = tmp_path / "sim.hdf5"
    with h5py.File(sim, "w") as f:
        f.create_dataset("mat", data=np.zeros((1, 4, 4), dtype=complex))
    with pytest.raises(ValueError, match=r"no dataset `state`.*QuSimulation"):
        quflow.read(sim)
    bad_n = tmp_path / "bad-n.hdf5"
    with h5py.File(bad_n, "w") as f:
        f.attrs["N"] = np.int64(5)
        f.create_dataset("state", data=np.zeros((1, 16)))
    with pytest.raises(ValueError, match=r"N = 5 does not match `state` rows of 16 = 4\^2"):
        quflow.read(bad_n)
    out = tmp_path / "out.hdf5"
    quflow.write(out, np.zeros(16))
    with pytest.raises(ValueError, match=r"the file has N = 4, the states N = 5"):
        quflow.write(out, np.zeros(25))
    with pytest.raises(ValueError, match=r"give time or qtime, not both"):
        quflow.write(out, np.zeros(16), time=[0.0], qtime=[0.0])
    with pytest.raises(ValueError, match=r"time: 2 values for 1 states"):
        quflow.write(out, np.zeros(16), time=[0.0, 1.0])
    with pytest.raises(ValueError, match=r"omegas: a coefficient is not finite"):
        quflow.write(out, np.full(16, np.nan))
    with pytest.raises(ValueError, match=r"harmonics\[0\]: \(l, m\) = \(4, 0\) is not a harmonic of N = 4"):
        quflow.omega_from_harmonics([[4, 0, 1.0]], 4)
    with h5py.File(tmp_path / "odd.hdf5", "w") as f:
        f.attrs["N"] = 4.5
        f.create_dataset("state", data=np.ones((1, 16)))
        f.create_dataset("data", data=[1.0])
        f.create_dataset("time", data=[np.nan])
    with pytest.raises(ValueError, match=r"the attribute N = 4.5 is not an integer"):
        quflow.read(tmp_path / "odd.hdf5")
    with pytest.raises(ValueError, match=r"'/data' is a dataset, not a group"):
        quflow.read(tmp_path / "odd.hdf5", datapath="/data")
    with h5py.File(tmp_path / "odd.hdf5", "a") as f:
        f.attrs["N"] = np.int64(4)
    with pytest.raises(ValueError, match=r"`time` at output 0 is nan, not finite"):
        quflow.read(tmp_path / "odd.hdf5")
    with pytest.raises(FileNotFoundError, match=r"no such file"):
        quflow.read(tmp_path / "missing.hdf5")
    with pytest.raises(ValueError, match=r"every coefficient with l >= 1 is zero"):
        quflow.zeitlin_spec(np.zeros(16), noise=[])
    with pytest.raises(ValueError, match=r"noise\[0\]: 9 coefficients, expected N\^2 = 16"):
        quflow.zeitlin_spec(np.ones(16), noise=[np.ones(9)])


def test_the_engines_fields_go_into_quflow_files_and_back(tmp_path):
    # The jet (linearly unstable at N = 64): its state and the state pushed
    # along its fastest-growing eigenvector, written in quflow's layout as
    # quflow's own integrator would start from them.
    fields = ec.zeitlin_fields(REPO / "fixtures" / "zeitlin" / "jet-n64.json")
    mode = fields["mode"]
    assert mode["kind"] == "unstable_eigenvector"
    committed = certificate("jet-n64")
    assert mode["rate"] == pytest.approx(committed["growth_rate"], rel=1e-6)
    path = tmp_path / "jet.hdf5"
    quflow.write(path, [fields["state"], fields["state"] + 1e-4 * mode["real"]], qtime=[0.0, 0.0])
    back0, back1 = quflow.read(path, step=0), quflow.read(path, step=1)
    assert np.array_equal(back0.omega, fields["state"]) and back0.N == 64
    assert np.allclose((back1.omega - back0.omega) / 1e-4, mode["real"], rtol=0, atol=1e-9)
    # The state read back certifies as the fixture did (its noise as given).
    spec = quflow.zeitlin_spec(path, step=0, noise=[fields["noise"][0]])
    cert = ec.certify(spec)
    assert cert.verdict == "linearly_unstable"
    assert cert.growth_rate == pytest.approx(committed["growth_rate"], rel=1e-8)
    # The zonal mode lives on one azimuthal wavenumber: |m| = block.
    for index in np.flatnonzero(np.abs(mode["real"]) > 1e-12):
        assert abs(quflow.ind2elm(int(index))[1]) == mode["block"]


def test_a_tilted_states_fields_read_back_to_its_axis(tmp_path):
    fields = ec.zeitlin_fields(REPO / "fixtures" / "zeitlin" / "tilted-energy-casimir-n32.json")
    assert fields["mode"]["kind"] == "fastest_growing_start"
    path = tmp_path / "tilted.hdf5"
    quflow.write(path, fields["state"], qtime=[0.0])
    cert = ec.certify(quflow.zeitlin_spec(path, noise=[fields["noise"][0]], settings={"casimir_momentum": False}))
    committed = certificate("tilted-energy-casimir-n32")
    assert cert["frame"]["axis"] == pytest.approx(committed["frame"]["axis"], abs=1e-12)
    assert cert.sigma2 == pytest.approx(committed["sigma2"], rel=1e-9)
    assert fields["mode"]["rate"] == pytest.approx(committed["sigma2"], rel=1e-6)
