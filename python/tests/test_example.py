"""The example script stays runnable and prints the CLI's sweep table (quick variant)."""

from __future__ import annotations

import csv
import io
import runpy
import sys
from contextlib import redirect_stdout

from conftest import ROOT, run_cli

EXAMPLE = ROOT / "python" / "examples" / "dh_crack_sweep.py"
CASES = [ROOT / "cases" / f"dh_crack_plate_{c}.toml" for c in ["k1_m1", "k1_m0.5", "k2_m1", "k2_m2"]]


def without_wall(text: str) -> list:
    """sweep.csv's rows without the wall-clock column (the only one that may differ)."""
    rows = list(csv.DictReader(io.StringIO(text)))
    for r in rows:
        r.pop("wall_seconds", None)
        r.pop("wall (s)", None)
    return rows


def test_example_reproduces_the_cli_sweep(cli, tmp_path, monkeypatch):
    out_py, out_cli = tmp_path / "py", tmp_path / "cli"
    monkeypatch.setattr(sys, "argv", [str(EXAMPLE), "--quick", "--out", str(out_py)])
    printed = io.StringIO()
    with redirect_stdout(printed):
        runpy.run_path(str(EXAMPLE), run_name="__main__")
    cli_out = run_cli(
        cli,
        "sweep",
        *CASES,
        "--vary",
        "time.end=0.005",
        "--vary",
        "time.outputs=[0.005]",
        "--out",
        out_cli,
    ).stdout
    py_csv = (out_py / "sweep.csv").read_text()
    assert without_wall(py_csv) == without_wall((out_cli / "sweep.csv").read_text())
    assert len(without_wall(py_csv)) == 4
    # the printed table: the CLI's lines, the wall-time cells aside
    def cells(text):
        return [
            [c for i, c in enumerate(line.split("|")) if i != wall]
            for line in text.splitlines()
            if line.startswith("| ")
        ]

    header = next(line for line in cli_out.splitlines() if line.startswith("| "))
    wall = next(i for i, c in enumerate(header.split("|")) if "wall" in c)
    assert cells(printed.getvalue()) == cells(cli_out)
    assert printed.getvalue().count("|---") == cli_out.count("|---")
