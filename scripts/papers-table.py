#!/usr/bin/env python3
"""The table "What the papers report, next to ours" of docs/validation.md: the figures the
papers print (quoted here, column 2) beside ours, read from the committed accuracy table
(validation/accuracy.json, written by scripts/benchmark-table.sh, which runs this at its end).
Writes validation/papers.json with the accuracy table's provenance; its checks stay in
accuracy.json. Usage: python3 scripts/papers-table.py   (from the repository root)"""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import figure_file  # noqa: E402

ACCURACY = "validation/accuracy.json"


def main():
    acc = json.load(open(ACCURACY))
    col = {name: k for k, name in enumerate(acc["columns"])}

    def cell(case, t, column):
        for row in acc["rows"]:
            if row[0] == case and float(row[1]) == t:
                return row[col[column]]
        raise SystemExit(f"{ACCURACY}: no row {case} at t = {t}")

    def probe(case, t):
        pd, classical = cell(case, t, "probe PD / classical (°C)").split(" / ")
        return f"PD {pd} °C at the midpoint node, series {classical} °C"

    def plates(t):
        names = [("1, 1", "dh_plate_k1_m1"), ("1, 2", "dh_plate_k1_m2"),
                 ("0.5, 1", "dh_plate_k0.5_m1"), ("0.5, 0.5", "dh_plate_k0.5_m0.5")]
        return ", ".join(f"**{cell(c, t, 'max abs diff (°C)')}** ({km})" for km, c in names)

    eq13 = lambda c, t: cell(c, t, "eq 13")
    rows = [
        ["Bobaru & Duangpanya 2010 Example 1, midpoint at t = 8 s", "classical 51.75 °C",
         f"{probe('bar_dirichlet', 8)} (eq 13 = {eq13('bar_dirichlet', 8)})"],
        ["Bobaru & Duangpanya 2010 Example 2, midpoint at t = 8 s", "classical 53.06 °C",
         f"{probe('bar_insulated_left', 8)} (eq 13 = {eq13('bar_insulated_left', 8)})"],
        ["Bobaru & Duangpanya 2010 Example 3, eq 45 at t = 8 s (constant kernel)",
         "3.43e-5 (triangular kernel: 2.84e-5)", f"**{cell('bar_flux', 8, 'eq 45')}**"],
        ["Bobaru & Duangpanya 2012 Example 2, eq 13 at t = 0.05 / 0.1 / 0.2 s, δ = 13L/240",
         "0.07927 / 0.05301 / 0.03203",
         " / ".join(f"**{eq13('square_one_hot_edge', t)}**" for t in (0.05, 0.1, 0.2))],
        ["Wang, Oterkus & Oterkus §4.1 plates (k, m) at 5 ms, max abs diff over all nodes",
         '"slight difference at the interface" (figures only)', f"{plates(0.005)} °C"],
        ["Wang, Oterkus & Oterkus §4.4 laser-heated film at 0.2 / 0.5 / 1 ps, max abs diff over all nodes",
         '"close agreement" with experiment (Fig. 28, figures only)',
         " / ".join(f"**{cell('laser_film', t, 'max abs diff (°C)')}**" for t in (2e-13, 5e-13, 1e-12))
         + " °C against the classical series"],
        ["Wang, Oterkus & Oterkus §4.5 split thermal shock at 3 s", '"good agreement" with FEM (Figs 29–30, figures only)',
         f"**{cell('thermal_shock_split', 3, 'max abs diff (°C)')}** °C over all nodes against the series"],
    ]
    figure_file.write("papers", "python3 scripts/papers-table.py (from validation/accuracy.json)",
                      ["benchmark", "paper's figure", "peritherm"], rows, source=acc["provenance"])


if __name__ == "__main__":
    main()
