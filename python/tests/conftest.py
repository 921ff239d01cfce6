"""Shared fixtures: the repository root, the CLI binary, and small variants of bundled cases.

The CLI is `target/release/peritherm` under the repository root (built with
`cargo build --release` if it is missing), or the program named by `PERITHERM_CLI`.
"""

from __future__ import annotations

import copy
import csv
import os
import subprocess
import tomllib
from pathlib import Path

import pytest

# every test computes the consistent weights it checks, and none writes to ~/.cache
os.environ.setdefault("PERITHERM_CACHE", "off")

ROOT = Path(__file__).resolve().parents[2]
CASES = ROOT / "cases"


@pytest.fixture(scope="session")
def cli() -> Path:
    named = os.environ.get("PERITHERM_CLI")
    if named:
        return Path(named)
    exe = ROOT / "target" / "release" / "peritherm"
    subprocess.run(
        ["cargo", "build", "--release", "--quiet", "--bin", "peritherm"],
        cwd=ROOT,
        check=True,
    )
    assert exe.exists(), exe
    return exe


def run_cli(cli: Path, *args: str) -> subprocess.CompletedProcess:
    """Runs the CLI from the repository root and fails the test on a non-zero exit."""
    p = subprocess.run(
        [str(cli), *map(str, args)], cwd=ROOT, capture_output=True, text=True
    )
    assert p.returncode == 0, p.stderr
    return p


def bundled(name: str) -> dict:
    """A bundled case file as a dict."""
    with open(CASES / f"{name}.toml", "rb") as f:
        return tomllib.load(f)


def small_case(kind: str) -> dict:
    """Small, quick variants of bundled cases, one per solver path of `peritherm run`."""
    if kind in ("euler", "rk4", "crank_nicolson", "bdf2", "adaptive", "steady"):
        d = bundled("dh_crack_plate_k2_m1")
        for r in d["region"]:
            r["spacing"] *= 5  # 1e-3 and 5e-4 m: about 1 000 nodes
        d["reference"]["fem"]["h"] = 5e-4
        d["reference"]["fem"]["dt"] = 0.01
        d["reference"]["exclude_tips"] = 3e-3
        d["time"] = {"end": 0.1, "outputs": [0.05, 0.1], "integrator": kind}
        if kind in ("crank_nicolson", "bdf2"):
            d["time"]["dt"] = 0.004
        if kind == "adaptive":
            d["time"]["integrator"] = "crank_nicolson"
            d["time"]["tolerance"] = 1e-3
        if kind == "steady":
            d["time"]["outputs"] = [0.1]
            del d["reference"]
        return d
    if kind == "enthalpy":
        d = bundled("planar_freezing")
        d["region"][0]["spacing"] = 0.02
        d["time"] = {"end": 43200.0, "outputs": [21600.0, 43200.0]}
        return d
    if kind == "history":
        # RK4 with a source; the history's samples (every 7e-15 s, not a multiple of dt)
        # are stops of the run too
        d = bundled("laser_film")
        d["region"][0]["spacing"] = 1e-9
        d["time"]["end"] = 5e-13
        d["time"]["outputs"] = [2e-13, 5e-13]
        d["history"]["interval"] = 7e-15
        return d
    if kind == "growing":
        d = bundled("growing_cracks")
        d["region"][0]["cells"] = [40, 40]
        d["time"] = {"end": 2.0, "outputs": [1.0, 2.0], "integrator": "euler"}
        return d
    raise KeyError(kind)


def write_case(d: dict, path: Path, peritherm) -> Path:
    """Writes the dict case as the TOML text `Case.from_dict` makes of it; returns the path."""
    case = peritherm.Case.from_dict(copy.deepcopy(d), path=str(path))
    path.write_text(case.source)
    return path


def read_csv(path: Path) -> dict:
    """A field CSV as columns of Python floats (correctly rounded: exact bits)."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}
