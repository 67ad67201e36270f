"""Sharded simulation from Python: shards merge into exactly the unsharded
report, shard files are one format with the CLI's (`verify simulate --shard`
and `--merge` read and write the same JSON), and sets that are not exactly
one study are refused with the file and the field named."""

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import energy_casimir as ec

REPO = Path(__file__).resolve().parents[2]
SPEC = REPO / "fixtures" / "rigid-body-major-axis.json"
# 700 paths are three blocks of 256 (the engine's unit of work), the last
# one short: shards of 2 and 3 split them unevenly.
OPTIONS = dict(paths=700, t_end=1.0, outputs=20, seed=5)


def same(a, b, at="$"):
    """Every number, array and string of two reports equal (not close)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), at
        for k in a:
            same(a[k], b[k], f"{at}.{k}")
    elif isinstance(a, np.ndarray):
        assert np.array_equal(a, np.asarray(b), equal_nan=True), at
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), at
        for i, (x, y) in enumerate(zip(a, b)):
            same(x, y, f"{at}[{i}]")
    else:
        assert a == b or (a != a and b != b), f"{at}: {a!r} vs {b!r}"


def verify_binary():
    # ./test.sh runs `cargo test --workspace` first, which builds the debug binary.
    for kind in ("debug", "release"):
        path = REPO / "target" / kind / "verify"
        if path.exists():
            return path
    pytest.skip("no verify binary under target/ (run ./test.sh)")


@pytest.fixture(scope="module")
def whole():
    return ec.simulate(SPEC, **OPTIONS)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_shards_merge_into_exactly_the_unsharded_report(whole, n):
    parts = [ec.simulate(SPEC, shard=(k, n), **OPTIONS) for k in range(n)]
    assert all(p["kind"] == "simulate-shard" for p in parts)
    # The shards' paths add up to the study's, each ensemble.
    assert sum(p["shard"]["nonlinear"]["paths"] for p in parts) == 700
    same(ec.merge_shards(SPEC, parts, **OPTIONS), whole)
    # In any order, from "k/n" text too, and the same shard twice is harmless.
    again = [ec.simulate(SPEC, shard=f"{k}/{n}", **OPTIONS) for k in reversed(range(n))]
    same(ec.merge_shards(SPEC, again + again[:1], **OPTIONS), whole)


def test_files_are_one_format_with_the_cli(whole, tmp_path):
    binary = verify_binary()
    args = ["--paths", "700", "--t-end", "1", "--outputs", "20", "--seed", "5"]
    for k in range(2):
        subprocess.run([str(binary), "simulate", str(SPEC), *args, "--shard", f"{k}/2", "--out", str(tmp_path)],
                       check=True, capture_output=True, timeout=600)
    cli_shards = sorted(tmp_path.glob("*.shard-*-of-2.json"))
    assert len(cli_shards) == 2
    # The CLI's shard files merge in Python (given as paths) ...
    same(ec.merge_shards(SPEC, cli_shards, **OPTIONS), whole)
    # ... and Python's, saved with json.dump, merge in the CLI into the same
    # numbers (the report's series; its other fields are the same study).
    py_dir = tmp_path / "py"
    py_dir.mkdir()
    files = []
    for k in range(2):
        path = py_dir / f"part-{k}.json"
        path.write_text(json.dumps(ec.simulate(SPEC, shard=(k, 2), **OPTIONS)))
        files.append(str(path))
    out = tmp_path / "merged"
    subprocess.run([str(binary), "simulate", str(SPEC), *args, "--out", str(out), "--merge", *files],
                   check=True, capture_output=True, timeout=600)
    report = json.loads(next(out.glob("*.json")).read_text())
    for key in ("times", "norm_mean_over_delta", "exceedance", "mean"):
        assert np.array_equal(np.asarray(report["nonlinear"][key]), whole["nonlinear"][key]), key
    assert np.array_equal(np.asarray(report["exact_moments_over_delta"]), whole["exact_moments_over_delta"])
    assert np.array_equal(np.asarray(report["histogram"]["counts"]), whole["histogram"]["counts"])


def test_sets_that_are_not_one_study_are_refused():
    parts = [ec.simulate(SPEC, shard=(k, 3), **OPTIONS) for k in range(3)]
    with pytest.raises(ValueError, match=r"incomplete: 1 of the 3 shards are missing \(1\)"):
        ec.merge_shards(SPEC, [parts[0], parts[2]], **OPTIONS)
    other_seed = ec.simulate(SPEC, shard=(1, 3), **{**OPTIONS, "seed": 6})
    with pytest.raises(ValueError, match=r"shards\[1\]: \$\.study\.seed: the shard belongs to another study"):
        ec.merge_shards(SPEC, [parts[0], other_seed, parts[2]], **OPTIONS)
    # Merged with other options than the shards ran with: named.
    with pytest.raises(ValueError, match=r"\$\.study\.paths"):
        ec.merge_shards(SPEC, parts, **{**OPTIONS, "paths": 800})
    two = ec.simulate(SPEC, shard=(1, 2), **OPTIONS)
    with pytest.raises(ValueError, match="shards of different splits do not merge"):
        ec.merge_shards(SPEC, [parts[0], two], **OPTIONS)
    edited = json.loads(json.dumps(parts[1]))
    edited["engine"] = "0.0.1"
    with pytest.raises(ValueError, match=r"shards\[1\]: \$\.engine: written by engine 0\.0\.1"):
        ec.merge_shards(SPEC, [parts[0], edited, parts[2]], **OPTIONS)
    with pytest.raises(ValueError, match=r"shards\[0\]: \$\.kind: not a shard"):
        ec.merge_shards(SPEC, [{"kind": "certificate"}], **OPTIONS)
    with pytest.raises(ValueError, match="shards: no shard files"):
        ec.merge_shards(SPEC, [], **OPTIONS)
    with pytest.raises(TypeError, match="a list of shard files or dicts, got one"):
        ec.merge_shards(SPEC, parts[0], **OPTIONS)


@pytest.mark.parametrize("bad", [(3, 3), (-1, 2), (0, 0), "1/0", "a/b", (True, 2), (0.5, 2), "2"])
def test_a_shard_that_does_not_exist_is_refused(bad):
    with pytest.raises(ValueError, match="shard: expected"):
        ec.simulate(SPEC, shard=bad, **OPTIONS)
