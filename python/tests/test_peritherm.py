"""peritherm from Python against the CLI: equal results bit for bit, errors, arrays, memory."""

from __future__ import annotations

import json
import os
import signal
import threading
import time

import numpy as np
import pytest

import peritherm
from conftest import ROOT, read_csv, run_cli, small_case, write_case

KINDS = [
    "euler",
    "rk4",
    "crank_nicolson",
    "bdf2",
    "adaptive",
    "steady",
    "enthalpy",
    "growing",
    "history",
]
COLUMNS = ["temperature", "damage", "qx", "qy", "qz"]


def same_bits(a, b) -> bool:
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


@pytest.mark.parametrize("kind", KINDS)
def test_run_equals_cli_bit_for_bit(kind, cli, tmp_path):
    """Model.run through the case's outputs gives the CLI's fields (temperature, damage and
    flux, every bit), and Model.write writes the CLI's field files byte for byte, adaptive
    steps included: their choice between conjugate gradients and a factorisation counts
    work, not seconds, so it is the same in every run.
    """
    path = write_case(small_case(kind), tmp_path / f"{kind}.toml", peritherm)
    run_cli(cli, "run", path, "--out", tmp_path / "cli", "--quiet")
    cli_summary = json.loads((tmp_path / "cli" / "run.json").read_text())
    model = peritherm.Model.from_case(path)
    outputs = model.run()
    assert [o["time"] for o in outputs] == model.case.outputs
    assert model.steps == cli_summary["steps"]
    for k, o in enumerate(outputs, start=1):
        f = read_csv(tmp_path / "cli" / f"field_{k}.csv")
        assert same_bits(o["temperature"], f["temperature"]), (kind, k)
        assert same_bits(o["damage"], f["damage"]), (kind, k)
        for c, col in enumerate(["qx", "qy", "qz"]):
            assert same_bits(o["flux"][:, c], f[col]), (kind, k, col)
    summary = model.write(tmp_path / "py")
    assert summary["fields"] == [f"field_{k}.csv" for k in range(1, len(outputs) + 1)]
    assert summary["fields"] == cli_summary["fields"]
    assert summary["output_times"] == cli_summary["output_times"]
    assert len(summary.get("reference", [])) == len(cli_summary.get("reference", []))
    assert summary["energy"] == cli_summary["energy"]
    assert summary.get("reference", []) == cli_summary.get("reference", [])
    for name in summary["fields"]:
        cli_text = (tmp_path / "cli" / name).read_bytes()
        assert (tmp_path / "py" / name).read_bytes() == cli_text, (kind, name)
        vtu = name.replace(".csv", ".vtu")
        assert (tmp_path / "py" / vtu).read_bytes() == (tmp_path / "cli" / vtu).read_bytes()
    assert (tmp_path / "py" / "case.toml").read_text() == (tmp_path / "cli" / "case.toml").read_text()


@pytest.mark.parametrize("kind", ["euler", "crank_nicolson", "enthalpy", "growing"])
def test_advance_to_equals_run(kind, tmp_path):
    """advance_to through the output times is run(): the same steps, the same bits."""
    path = write_case(small_case(kind), tmp_path / "case.toml", peritherm)
    a = peritherm.Model.from_case(path)
    b = peritherm.Model.from_case(path)
    outputs = a.run()
    for o in outputs:
        b.advance_to(o["time"])
        assert b.time == o["time"]
        assert same_bits(b.temperature[: b.n_body], o["temperature"])
        assert same_bits(b.flux(), o["flux"])
        assert same_bits(b.damage(), o["damage"])
        assert b.energy() == o["energy"]
    assert a.steps == b.steps > 0


def test_run_case_equals_cli(cli, tmp_path):
    """run_case is `peritherm run`: the same field files, and run.json's measures."""
    path = write_case(small_case("euler"), tmp_path / "case.toml", peritherm)
    run_cli(cli, "run", path, "--out", tmp_path / "cli", "--quiet")
    s = peritherm.run_case(str(path), tmp_path / "py")
    assert s["status"] == "complete" and s["steps"] > 0
    assert [c["time"] for c in s["reference"]] == [0.05, 0.1]
    assert all(c["max_abs_diff"] >= 0 for c in s["reference"])
    for name in s["fields"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()


def test_fem_equals_cli(cli, tmp_path):
    path = write_case(small_case("euler"), tmp_path / "case.toml", peritherm)
    run_cli(cli, "fem", path, "--out", tmp_path / "cli", "--h", "1e-3", "--quiet")
    s = peritherm.fem(path, tmp_path / "py", h=1e-3)
    assert s["solver"] == "fem"
    for name in s["fields"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()


@pytest.mark.parametrize("kind", ["euler", "rk4", "crank_nicolson", "enthalpy"])
def test_written_temperature_then_stepping_equals_cli_initial_field(kind, cli, tmp_path):
    """Writing `temperature` at t = 0 and running equals the CLI run of the same case with
    that field as its `[initial] value` expression."""
    expr = "20 + 500*x - 300*y" if kind != "enthalpy" else "270 + 15*x"
    d = small_case(kind)
    with_field = dict(d, initial={"value": expr})
    path = write_case(with_field, tmp_path / "initial.toml", peritherm)
    run_cli(cli, "run", path, "--out", tmp_path / "cli", "--quiet")
    model = peritherm.Model.from_case(peritherm.Case.from_dict(d, path=tmp_path / "zero.toml"))
    x, y = model.positions[: model.n_body, 0], model.positions[: model.n_body, 1]
    field = 20 + 500 * x - 300 * y if kind != "enthalpy" else 270 + 15 * x
    model.temperature = field
    # the field as the CLI evaluates it, at the body nodes the boundary does not drive
    reference = peritherm.Model.from_case(path)
    assert same_bits(model.temperature, reference.temperature)
    outputs = model.run()
    for k, o in enumerate(outputs, start=1):
        f = read_csv(tmp_path / "cli" / f"field_{k}.csv")
        assert same_bits(o["temperature"], f["temperature"]), (kind, k)


def test_bad_cases_raise_value_error_naming_the_key(tmp_path):
    d = small_case("euler")
    d["time"]["dt"] = -1.0
    with pytest.raises(ValueError, match=r"time\.dt"):
        peritherm.Model.from_case(peritherm.Case.from_dict(d))
    d = small_case("euler")
    d["region"][1]["spacing"] = "fine"
    with pytest.raises(ValueError, match=r"<dict>: region\[1\]\.spacing: invalid type"):
        peritherm.Case.from_dict(d)
    d = small_case("euler")
    d["time"]["outputs"] = [0.2]  # after the end
    with pytest.raises(ValueError, match=r"time\.outputs"):
        peritherm.Case.from_dict(d)
    d = small_case("euler")
    d["material"]["plate"]["conductivity"] = -114.0
    with pytest.raises(ValueError, match=r"conductivity"):
        peritherm.Model.from_case(peritherm.Case.from_dict(d))
    with pytest.raises(ValueError, match=r"missing\.toml: -: cannot read"):
        peritherm.Case.load(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text('title = "x"\ndimension = 2\n[time]\nend = "soon"\n')
    with pytest.raises(ValueError, match=r"bad\.toml"):
        peritherm.Model.from_case(bad)
    with pytest.raises(ValueError, match="temperature"):
        m = peritherm.Model.from_case(peritherm.Case.from_dict(small_case("euler")))
        m.temperature = np.zeros(3)
    with pytest.raises(ValueError, match="cannot be written as TOML"):
        peritherm.Case.from_dict({"title": object()})


def test_arrays_have_the_documented_shapes_and_dtypes():
    m = peritherm.Model.from_case(peritherm.Case.from_dict(small_case("growing")))
    n, nb = m.n_nodes, m.n_body
    assert 0 < nb <= n
    expect = {
        "positions": ((n, 3), np.float64),
        "volumes": ((n,), np.float64),
        "spacing": ((n,), np.float64),
        "horizon": ((n,), np.float64),
        "region": ((n,), np.int32),
        "temperature": ((n,), np.float64),
        "neighbor_indices": ((m.n_bonds,), np.int64),
    }
    for name, (shape, dtype) in expect.items():
        a = getattr(m, name)
        assert a.shape == shape and a.dtype == dtype, name
    off = m.neighbor_offsets
    assert off.dtype == np.int64 and off[0] == 0 and off[-1] == m.n_bonds
    assert np.all(np.diff(off) >= 0)
    idx = m.neighbor_indices
    assert idx.min() >= 0 and idx.max() < n
    assert m.flux().shape == (nb, 3) and m.flux().dtype == np.float64
    assert m.damage().shape == (nb,) and m.damage().dtype == np.float64
    # copies: writing into them changes nothing
    t = m.temperature
    t[:] = 1e9
    assert m.temperature.max() < 1e9
    out = m.run([0.5])[0]
    assert out["temperature"].shape == (nb,) and out["flux"].shape == (nb, 3)
    assert m.time == 0.5
    assert 0 < m.dt <= m.stable_dt()
    assert np.isfinite(m.energy())


def rss_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_no_memory_growth_over_1000_steps():
    """1 000 step() calls (and temperature reads) keep the resident set within 4 MiB.

    The model has about 4 000 nodes, so keeping one temperature array per call would grow
    by 32 MB and one flux array by 96 MB; 4 MiB leaves room for allocator arenas and
    Python's own caches, which settle during the 100 warm-up calls.
    """
    m = peritherm.Model.from_case(peritherm.Case.from_dict(small_case("growing")))
    assert m.n_nodes >= 1600
    for _ in range(100):
        m.step(1)
        _ = m.temperature
    before = rss_bytes()
    for _ in range(1000):
        m.step(1)
        _ = m.temperature
    grown = rss_bytes() - before
    assert m.steps == 1100
    assert grown < 4 * 2**20, f"RSS grew by {grown} bytes"


def test_ctrl_c_interrupts_stepping():
    """SIGINT during a long step() raises KeyboardInterrupt between steps, GIL released."""
    m = peritherm.Model.from_case(peritherm.Case.from_dict(small_case("euler")))
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    started = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        m.step(10**9)
    assert time.monotonic() - started < 30
    assert 0 < m.steps < 10**9 and m.time > 0
    m.step(1)  # still usable


def test_ctrl_c_interrupts_run_case_and_leaves_out_as_it_was(tmp_path):
    """SIGINT during run_case raises KeyboardInterrupt; no output directory and no staged
    copy are left behind."""
    d = small_case("euler")
    del d["reference"]
    d["time"] = {"end": 1e4, "outputs": [1e4]}  # about 1e6 steps: minutes
    path = write_case(d, tmp_path / "long.toml", peritherm)
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    started = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        peritherm.run_case(path, tmp_path / "out")
    assert time.monotonic() - started < 30
    assert sorted(p.name for p in tmp_path.iterdir()) == ["long.toml"]


def test_dict_and_file_give_the_same_case():
    path = ROOT / "cases" / "dh_crack_plate_k2_m1.toml"
    import tomllib

    with open(path, "rb") as f:
        d = tomllib.load(f)
    a = peritherm.Case.load(path)
    b = peritherm.Case.from_dict(d, path=path)
    assert (a.title, a.end, a.outputs, a.integrator) == (b.title, b.end, b.outputs, b.integrator)


def test_sweep_against_first_compares_with_the_first_variant(tmp_path):
    """`against_first=True` (`--against-first`) compares with the first variant although the
    case has its own reference (the series): the first variant's row is zero, the second's is
    not; giving it with `against` is a ValueError naming both."""
    case = str(ROOT / "cases" / "bar_dirichlet.toml")
    vary = ["region.*.horizon.radius=0.3,0.15", "time.outputs=[0.1]"]
    r = peritherm.sweep([case], str(tmp_path / "s"), vary=vary, against_first=True)
    rows = r["rows"]
    assert len(rows) == 2
    assert rows[0]["max_abs"] == 0.0 and rows[1]["max_abs"] > 1.0
    assert all(row["against"].endswith(rows[0]["label"]) for row in rows)
    with pytest.raises(ValueError, match="against, against_first"):
        peritherm.sweep([case], str(tmp_path / "t"), vary=vary, against=str(tmp_path / "s"),
                        against_first=True)
