"""Box certificates (docs/boxes.md) from Python: a spec with a ``box``
section certifies every parameter in the box, and ``check`` re-proves it."""

import copy

import pytest

import energy_casimir as ec


def rigid_body_box():
    return {
        "name": "rigid-body-box",
        "algebra": "so3",
        "parameters": {"I1": 3, "I2": 2, "I3": 1, "sigma": "3/10"},
        "hamiltonian": "Pi1^2/(2*I1) + Pi2^2/(2*I2) + Pi3^2/(2*I3)",
        "casimirs": ["(Pi1^2 + Pi2^2 + Pi3^2)/2"],
        "equilibrium": [1, 0, 0],
        "noise": [["sigma", 0, 0]],
        "box": {"parameters": {"I2": ["3/2", "5/2"], "I3": ["4/5", "6/5"]}},
    }


def test_a_box_certifies_and_checks_with_the_closed_form_sup():
    cert = ec.certify(rigid_body_box())
    assert cert.verdict == "stable"
    d = cert.to_dict()
    # Sigma^2 = sigma^2 (b/a - 1), a = 1/I2 - 1/I1, b = 1/I3 - 1/I1: largest
    # at (I2, I3) = (5/2, 4/5), 0.09 * (55/4 - 1) = 1.1475 (by hand)
    assert 1.1475 <= d["sup_sigma2"] <= 1.1475 * 1.0011
    assert d["sampled_max"]["at"] == ["5/2", "4/5"]
    assert ec.check(cert).verdict == "stable"
    forged = copy.deepcopy(d)
    forged["sub_boxes"][0]["sign"] = -1
    with pytest.raises(ec.CheckError) as e:
        ec.check(forged)
    assert e.value.kind == "failed"


def test_a_bad_box_names_the_field():
    spec = rigid_body_box()
    spec["box"]["parameters"]["I2"] = ["5/2", "3/2"]
    with pytest.raises(ec.SpecError) as e:
        ec.certify(spec)
    assert e.value.path == "$.box.parameters.I2"


def test_a_residual_that_vanishes_in_the_box_is_a_statement_about_part_of_it():
    # mu_e = (1, I2 - 2, 0) is an equilibrium only at I2 = 2, the spec's own
    # value, where the body is stable: the box is not called
    # not_an_equilibrium as a whole, and check claims nothing for the spec's
    # own point
    spec = rigid_body_box()
    spec["equilibrium"] = [1, "I2-2", 0]
    spec["box"] = {"parameters": {"I2": ["3/2", "5/2"]}}
    cert = ec.certify(spec)
    assert cert.verdict == "partly_not_an_equilibrium"
    assert cert.kind == "box"
    assert "nothing is claimed" in cert.reason
    assert cert.theorem.startswith("Proved (exact), on part of the box")
    assert "nonlinear" in cert.not_checked
    assert ec.check(cert).verdict == "inconclusive"
    point = dict(spec)
    del point["box"]
    assert ec.certify(point).verdict == "stable"
