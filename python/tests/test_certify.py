"""The Python package against independent derivations (closed forms and a
numpy reconstruction of the generator), bad input, round trips and
concurrent calls. Nothing here compares the engine with its own output
except the byte-identity of the certificate text with the CLI's committed
fixture (the contract that both front ends write the same certificate)."""

import json
import math
import random
import subprocess
import sys
import types
from concurrent.futures import ThreadPoolExecutor
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

import energy_casimir as ec

REPO = Path(__file__).resolve().parents[2]
FIXTURES = REPO / "fixtures"


def rigid_body(i1, i2, i3, sigma, name="rigid-body"):
    return {
        "name": name,
        "algebra": "so3",
        "parameters": {"I1": str(i1), "I2": str(i2), "I3": str(i3), "sigma": str(sigma)},
        "hamiltonian": "Pi1^2/(2*I1) + Pi2^2/(2*I2) + Pi3^2/(2*I3)",
        "equilibrium": [1, 0, 0],
        "noise": [["sigma", 0, 0]],
        "stopping": {"epsilon": 0.1, "delta": 0.001},
    }


def rigid_body_sigma2(i1, i2, i3, sigma):
    """Closed form (generator::closed_forms, derived in docs/errata.md):
    a_i = 1/I_i - 1/I1; stable iff a2 a3 > 0, and then
    Sigma^2 = sigma^2 (max(|a2|,|a3|)/min(|a2|,|a3|) - 1)."""
    a2, a3 = 1 / i2 - 1 / i1, 1 / i3 - 1 / i1
    if a2 * a3 <= 0:
        return None
    lo, hi = sorted([abs(a2), abs(a3)])
    return sigma * sigma * (hi / lo - 1)


def test_rigid_body_closed_form_over_random_inertias():
    rng = random.Random(7)
    for _ in range(25):
        i = [Fraction(rng.randint(1, 40), rng.randint(1, 9)) for _ in range(3)]
        if len(set(i)) < 3:
            continue
        sigma = Fraction(rng.randint(1, 200), 100)
        cert = ec.certify(rigid_body(*i, sigma))
        expected = rigid_body_sigma2(*i, sigma)
        if expected is None:
            # Intermediate axis: A has the real eigenvalues +-sqrt(-a2 a3).
            assert cert.verdict == "linearly_unstable"
            a2, a3 = 1 / i[1] - 1 / i[0], 1 / i[2] - 1 / i[0]
            assert cert.growth_rate == pytest.approx(math.sqrt(float(-a2 * a3)), rel=1e-12)
        else:
            assert cert.verdict == "stable"
            assert cert.level == "exact"
            assert cert.sigma2_exact == expected
            assert cert.sigma2 == float(expected)


def test_extreme_inertias_keep_the_exact_closed_form():
    """I1 = 1e308 and I3 = 1e-308 (exact rationals; a double would overflow
    1/I3): the certified Sigma^2 is a proved bound for its own P, so it can
    never lie below the family's sharp constant (the closed form), and the
    engine keeps it within 1e-12 of it."""
    for i in [(Fraction(10) ** 308, 2, 1), (3, 2, Fraction(1, 10**308))]:
        i = tuple(Fraction(x) for x in i)
        spec = rigid_body(*i, Fraction(3, 10))
        spec["parameters"].update(I1=format_rational(i[0]), I3=format_rational(i[2]))
        cert = ec.certify(spec)
        if i[2] < 1 and cert.verdict == "inconclusive":
            # cond(P) ~ 1e308: the search's relative margin cannot resolve
            # definiteness in floating point, and the engine claims nothing.
            continue
        assert cert.verdict == "stable"
        sharp = rigid_body_sigma2(*i, Fraction(3, 10))
        assert sharp <= cert.sigma2_exact <= sharp * (1 + Fraction(1, 10**12))


def format_rational(q):
    return f"{q.numerator}/{q.denominator}"


def test_generator_form_rebuilt_in_numpy():
    """Q = sym(P A~ + A~^T P + B^T P B), A~ = A + B^2/2, rebuilt from the
    Euler equations dPi = Pi x Omega dt + Pi x (sigma e1) o dW (the sign of
    B does not matter: Q is even in B), and P conserved: P A + A^T P = 0."""
    i1, i2, i3, sigma = 3.0, 2.0, 1.0, 0.3
    cert = ec.certify(FIXTURES / "rigid-body-major-axis.json")
    P, Q = cert.P, cert.Q

    def cross(v):
        return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])

    pe = np.array([1.0, 0, 0])
    inv_i = np.diag([1 / i1, 1 / i2, 1 / i3])
    omega_e = inv_i @ pe
    # d/dx [(Pi_e + x) x I^{-1}(Pi_e + x)] at x = 0.
    A = cross(pe) @ inv_i - cross(omega_e)
    B = -cross(np.array([sigma, 0, 0]))  # x -> x x (sigma e1)
    assert np.abs(P @ A + A.T @ P).max() < 1e-14
    At = A + 0.5 * B @ B
    q = P @ At + At.T @ P + B.T @ P @ B
    assert np.allclose(Q, 0.5 * (q + q.T), atol=1e-14)
    # Sigma^2 = lambda_max(Q, P), P positive definite here.
    L = np.linalg.cholesky(P)
    Li = np.linalg.inv(L)
    top = np.linalg.eigvalsh(Li @ Q @ Li.T).max()
    assert cert.sigma2 == pytest.approx(top, rel=1e-12)
    assert cert.sigma2 == pytest.approx(0.27, rel=1e-15)  # 0.09 * (1/(1/2) - 1) ... closed form 3 sigma^2


def test_fluctuating_lagrange_top_closed_form():
    """Sigma^2 = 4 sigma^2 / (p^2 - 4 mgl I1) at the optimal multiplier
    (generator::closed_forms): 4 * 0.09 / (9 - 4) = 9/125 for the fixture."""
    spec = json.loads((FIXTURES / "lagrange-top-fluctuating-gravity.json").read_text())
    for p, mgl in [(3, 1), (5, 2), (Fraction(7, 2), Fraction(1, 2))]:
        spec["parameters"].update({"p": str(p), "mgl": str(mgl)})
        cert = ec.certify(spec)
        sigma = Fraction(3, 10)
        expected = 4 * sigma**2 / (Fraction(p) ** 2 - 4 * Fraction(mgl) * 1)
        assert cert.verdict == "stable"
        assert cert.sigma2 == pytest.approx(float(expected), rel=1e-9)


def test_stopping_time_is_a_guarantee():
    cert = ec.certify(FIXTURES / "rigid-body-major-axis.json")
    t = cert.stopping_time(0.1, 0.001)
    exact = math.log(100) / 0.27
    assert exact * (1 - 1e-14) < t <= exact
    assert cert.stopping["T"] == pytest.approx(t, rel=1e-15)
    with pytest.raises(ValueError):
        cert.stopping_time(0.001, 0.1)
    zero = ec.certify(FIXTURES / "lagrange-top-fast.json")
    assert zero.sigma2 == 0 and zero.stopping_time(0.1, 0.001) == math.inf
    unstable = ec.certify(FIXTURES / "rigid-body-intermediate-axis.json")
    with pytest.raises(ValueError):
        unstable.stopping_time(0.1, 0.001)


def test_every_verdict_path():
    expected = {
        "rigid-body-major-axis": "stable",
        "rigid-body-intermediate-axis": "linearly_unstable",
        "rigid-body-spherical": "inconclusive",
        "rigid-body-not-equilibrium": "not_an_equilibrium",
        "rigid-body-isotropic-noise": "noise_incompatible",
    }
    for name, verdict in expected.items():
        cert = ec.certify(FIXTURES / f"{name}.json")
        assert cert.verdict == verdict, name
        assert ec.check(cert).verdict == verdict


def test_certificate_is_the_clis_and_round_trips(tmp_path):
    path = FIXTURES / "heavy-top-asymmetric.json"
    cert = ec.certify(path)
    assert cert.to_json() == (FIXTURES / "heavy-top-asymmetric.cert.json").read_text()
    # Every input form gives the same certificate.
    text = path.read_text()
    assert ec.certify(text).to_json() == cert.to_json()
    assert ec.certify(json.loads(text)).to_json() == cert.to_json()
    assert ec.certify(str(path)).to_json() == cert.to_json()
    # And every form of the certificate checks.
    out = tmp_path / "c.json"
    cert.save(out)
    for form in (cert, cert.to_dict(), cert.to_json(), out, str(out)):
        report = ec.check(form)
        assert (report.verdict, report.level) == ("stable", "exact")
        assert report.sigma2 == cert.sigma2


def test_fluid_zeitlin_and_large_specs():
    z = ec.certify(FIXTURES / "zeitlin" / "quflow-tilted-n16.json")  # reads two .npy files beside it
    assert (z.kind, z.verdict, z.level) == ("zeitlin", "stable", "verified_float")
    assert z.sigma2_upper >= z.sigma2 > 0
    assert ec.check(z).verdict == "stable"
    big = ec.certify(FIXTURES / "large" / "chain-30.json")
    # Uncoupled copies of the major-axis body: the single body's 0.27.
    assert big.kind == "large" and big.sigma2 == pytest.approx(0.27, rel=1e-9)
    # The verified final check (docs/large.md): a proved bound at or above it.
    assert big.level == "verified_float" and 0.27 <= big.sigma2_upper <= 0.27 * 1.01


def test_altered_certificates_fail_with_the_path():
    d = ec.certify(FIXTURES / "rigid-body-major-axis.json").to_dict()
    cases = [
        ("sigma2", 0.27 * (1 - 1e-7), "$.sigma2"),
        # The checker names the first field that differs from its
        # re-derivation: the level comes before the verdict.
        ("verdict", "inconclusive", "$.level"),
        # sigma2 must be the double nearest sigma2_exact: that is checked first.
        ("sigma2_exact", "26/100", "$.sigma2"),
    ]
    for key, value, path in cases:
        bad = json.loads(json.dumps(d))
        bad[key] = value
        with pytest.raises(ec.CheckError) as e:
            ec.check(bad)
        assert e.value.path == path and e.value.kind == "failed", (key, e.value)
    bad = json.loads(json.dumps(d))
    bad["P"][0][0] = "1/3"
    with pytest.raises(ec.CheckError) as e:
        ec.check(bad)
    assert e.value.path.startswith("$.P")
    with pytest.raises(ec.CheckError) as e:
        ec.check({"verdict": "stable"})
    assert e.value.kind == "bad_input" and e.value.path.startswith("$")


@pytest.mark.parametrize(
    "edit, path",
    [
        (lambda s: s.update(equilibrium=[1, 0]), "$.equilibrium"),
        (lambda s: s.update(noise=[["sigma", 0]]), "$.noise[0]"),
        (lambda s: s.update(hamiltonian="Pi1^2/(2*I1"), "$.hamiltonian"),
        (lambda s: s.update(algebra="so7"), "$.algebra"),
        (lambda s: s["parameters"].update(I1="abc"), "$.parameters.I1"),
        (lambda s: s["parameters"].update(I1="0"), "$.hamiltonian"),  # division by zero
        (lambda s: s.pop("noise"), "$.noise"),
    ],
)
def test_bad_input_names_the_field(edit, path):
    spec = rigid_body(3, 2, 1, Fraction(3, 10))
    edit(spec)
    with pytest.raises(ec.SpecError) as e:
        ec.certify(spec)
    assert isinstance(e.value, ValueError)
    assert e.value.path.startswith(path), e.value
    assert e.value.message


def test_fractions_and_numpy_values_in_a_dict_spec():
    """Fractions are written as exact "p/q" strings and numpy values as
    numbers: the same certificate as the fixture's strings."""
    spec = rigid_body(3, 2, 1, Fraction(3, 10))
    spec["parameters"] = {"I1": np.int64(3), "I2": 2, "I3": Fraction(1), "sigma": Fraction(3, 10)}
    spec["equilibrium"] = np.array([1, 0, 0])
    cert = ec.certify(spec)
    assert cert.sigma2_exact == Fraction(27, 100)


def test_bad_arguments():
    with pytest.raises(FileNotFoundError):
        ec.certify("no/such/spec.json")
    with pytest.raises(TypeError):
        ec.certify(42)
    with pytest.raises(ec.SpecError) as e:
        ec.certify("{not json")
    assert e.value.path == "$"
    with pytest.raises(ValueError):
        ec.certify({"x": float("nan")})


def test_concurrent_calls_agree():
    specs = [rigid_body(3, 2, 1, Fraction(k, 10), name=f"b{k}") for k in range(1, 9)]
    with ThreadPoolExecutor(max_workers=4) as pool:
        certs = list(pool.map(ec.certify, specs * 3))
    for k, cert in enumerate(certs):
        sigma = Fraction(k % 8 + 1, 10)
        assert cert.sigma2_exact == 3 * sigma**2  # closed form, I = (3, 2, 1)
    with ThreadPoolExecutor(max_workers=4) as pool:
        reports = list(pool.map(ec.check, certs))
    assert all(r.verdict == "stable" for r in reports)


def test_errors_pickle_with_their_fields_and_read_errors_keep_their_kind(tmp_path):
    """Exceptions cross process boundaries (multiprocessing pickles them)."""
    import pickle

    with pytest.raises(ec.SpecError) as e:
        ec.certify({"name": "x", "algebra": "so3", "hamiltonian": "Pi1^2", "equilibrium": [1, 0], "noise": []})
    back = pickle.loads(pickle.dumps(e.value))
    assert type(back) is ec.SpecError and back.path == "$.equilibrium" and back.message == e.value.message
    assert type(e.value).__module__ == "energy_casimir._core"
    with pytest.raises(IsADirectoryError):
        ec.certify(tmp_path)
    with pytest.raises(ValueError):
        ec.certify("   ")


ZEITLIN_1024 = {
    "name": "zeitlin-n1024-energy",
    "zeitlin": {"N": 1024, "equilibrium": "z + 0.3*z^3", "noise": ["0.1*z^2"]},
    "settings": {"casimir_momentum": False},
}


def test_ctrl_c_ends_a_long_certify(interrupted):
    """The energy–Casimir–momentum search of a Zeitlin state at N = 1024
    takes 7 to 10 s; SIGINT two seconds in raises KeyboardInterrupt at
    once."""
    interrupted(f"certify({ZEITLIN_1024!r})", 2.0)


def test_ctrl_c_stops_the_work_itself_and_progress_moved_before():
    """After the KeyboardInterrupt no engine thread is left working: the
    process then uses (almost) no CPU time while it sleeps for a second
    (an abandoned search kept a core busy for some 8 s more). The progress
    callback was called, with counts that only grow and stay within the
    total, before the interrupt."""
    # (SIGINT's handler installed, as in conftest's `interrupted`: a child of
    # a shell's background job inherits SIGINT ignored)
    code = f"""
import os, signal, threading, time
signal.signal(signal.SIGINT, signal.default_int_handler)
import energy_casimir as ec
calls = []
threading.Timer(2.0, os.kill, (os.getpid(), signal.SIGINT)).start()
try:
    ec.certify({ZEITLIN_1024!r}, progress=lambda d, t: calls.append((d, t)))
    print("finished")
except KeyboardInterrupt:
    print("interrupted")
c0 = time.process_time()
time.sleep(1.0)
print("cpu", time.process_time() - c0)
print("calls", len(calls), all(a[0] <= b[0] for a, b in zip(calls, calls[1:])), all(0 <= d <= t for d, t in calls), calls[-1] if calls else None)
"""
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=120)
    lines = out.stdout.splitlines()
    assert lines[0] == "interrupted", out
    cpu = float(lines[1].split()[1])
    assert cpu < 0.2, f"{cpu} s of CPU after the interrupt: the work went on"
    _, count, monotone, bounded, last = lines[2].split(" ", 4)
    assert int(count) >= 5 and monotone == "True" and bounded == "True", lines[2]
    done, total = eval(last)
    assert 0 < done < total, "the search was under way, not over"


def test_progress_of_certify_and_check_ends_at_the_total():
    """A fluid spec (x-mode solves) and a Zeitlin certificate's check (block
    operations): the last call is (total, total) with total > 1, and the
    counts only grow."""
    for run in (
        lambda cb: ec.certify(FIXTURES / "fluids" / "compressible-compatible-noise.json", progress=cb),
        lambda cb: ec.check(ec.certify(FIXTURES / "zeitlin" / "quflow-tilted-n16.json"), progress=cb),
    ):
        calls = []
        run(lambda d, t: calls.append((d, t)))
        assert calls and calls[-1][0] == calls[-1][1] > 1, calls
        assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:]))
    # A finite-dimensional spec is one step.
    calls = []
    ec.certify(FIXTURES / "rigid-body-major-axis.json", progress=lambda d, t: calls.append((d, t)))
    assert calls[-1] == (1, 1)


def test_progress_true_draws_tqdm_or_a_text_line(monkeypatch, capsys):
    """``progress=True``: a tqdm bar when tqdm imports (a stand-in module
    records what the bar was told), else a line on standard error."""
    told = []

    class Bar:
        def __init__(self, total, desc, unit):
            self.total, self.n = total, 0
            told.append(("open", desc))

        def update(self, k):
            self.n += k
            told.append(("at", self.n, self.total))

        def close(self):
            told.append(("close",))

    fake = types.ModuleType("tqdm.auto")
    fake.tqdm = Bar
    monkeypatch.setitem(sys.modules, "tqdm", types.ModuleType("tqdm"))
    monkeypatch.setitem(sys.modules, "tqdm.auto", fake)
    ec.certify(FIXTURES / "rigid-body-major-axis.json", progress=True)
    assert told[0] == ("open", "certify") and told[-1] == ("close",) and told[-2] == ("at", 1, 1), told
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)  # import fails
    ec.certify(FIXTURES / "rigid-body-major-axis.json", progress=True)
    assert "certify: 1/1 steps (100%)" in capsys.readouterr().err
    with pytest.raises(TypeError, match="progress"):
        ec.certify(FIXTURES / "rigid-body-major-axis.json", progress="yes")
