"""A spec given as a dict (or JSON text) has no folder of its own: the files
it names (a Zeitlin field's ``.npy``) are read from the current folder. The
error said "the spec's folder" without saying how to give one; it now names
``base_dir=``, and following it works."""

import json
from pathlib import Path

import pytest

import energy_casimir as ec

REPO = Path(__file__).resolve().parents[2]
ZEITLIN = REPO / "fixtures" / "zeitlin"


def quflow_spec():
    # Names quflow-tilted-n16-W.npy and -X.npy, which lie beside the file.
    return json.loads((ZEITLIN / "quflow-tilted-n16.json").read_text())


def test_a_dict_spec_naming_npy_files_says_how_to_pass_base_dir(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # no .npy here
    spec = quflow_spec()
    for call in (ec.certify, ec.validate):
        with pytest.raises(ec.SpecError) as e:
            call(spec)
        assert e.value.path == "$.zeitlin.equilibrium.npy"
        assert "base_dir=" in e.value.message and "base_dir=" in str(e.value), str(e.value)
        assert "current folder" in e.value.message
    # JSON text has no folder either
    with pytest.raises(ec.SpecError) as e:
        ec.certify(json.dumps(spec))
    assert "base_dir=" in str(e.value)
    # Following the advice works; a spec file needs none (its folder is the base).
    assert ec.certify(spec, base_dir=ZEITLIN).verdict == "stable"
    assert ec.certify(ZEITLIN / "quflow-tilted-n16.json").verdict == "stable"


def test_a_wrong_base_dir_is_named_not_advised(tmp_path):
    # base_dir was given (the wrong one): the message names that folder and
    # does not tell the user to pass what they passed.
    with pytest.raises(ec.SpecError) as e:
        ec.certify(quflow_spec(), base_dir=tmp_path)
    assert "the spec's folder" in e.value.message and tmp_path.name in e.value.message
    assert "base_dir=" not in str(e.value)
