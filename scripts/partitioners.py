#!/usr/bin/env python3
"""Compares the partition a distributed run uses (contiguous ranges of the node order, cut by
work) with METIS's k-way graph partition of the bond graph, on bundled cases, and writes the
table as the figure file validation/partitioners.json (docs/distributed.md shows it; run
scripts/update-docs.sh after this).

Work per body node: its bonds + 4 (a row's fixed cost), the weight both partitioners balance.
Per rank: ghosts are the distinct body nodes outside the rank that its rows read (fictitious
nodes are left out: their publishers send them at outputs only), neighbours the ranks it
receives from. The contiguous cut is by the actual bonds here; a run cuts by an estimate of
them from the cloud (`Partition::by_estimate`), which `peritherm partition` reports.

Needs the Python package and METIS's binding: pip install ./python pymetis numpy
Usage: python3 scripts/partitioners.py [CASE ...]
"""
import os
import sys

import figure_file

import numpy as np
import peritherm
import pymetis

RANKS = [2, 8, 64, 512]
CASES = ["cases/crack_plate_refined.toml", "cases/dh_plate_gmsh_k0.5_m1.toml", "cases/dh_crack_plate_k1_m1.toml"]


def body_graph(model):
    """Body-to-body CSR of the bonds, and each body node's work (bonds + 4)."""
    nb = model.n_body
    off = np.asarray(model.neighbor_offsets)[: nb + 1]
    idx = np.asarray(model.neighbor_indices)[: off[nb]]
    work = np.diff(off) + 4
    rows = np.repeat(np.arange(nb), np.diff(off))
    keep = idx < nb
    return rows[keep], idx[keep], work


def contiguous(work, ranks):
    """Part of each node: contiguous ranges with about equal cumulative work."""
    cum = np.cumsum(work)
    return np.minimum((cum - 1) * ranks // cum[-1], ranks - 1)


def metis(rows, cols, work, ranks):
    """Part of each node: METIS k-way on the symmetrised bond graph, balancing work."""
    n = len(work)
    pairs = np.unique(np.concatenate([rows * n + cols, cols * n + rows]))
    a, b = pairs // n, pairs % n
    xadj = np.concatenate([[0], np.cumsum(np.bincount(a, minlength=n))])
    graph = pymetis.CSRAdjacency(adj_starts=xadj, adjacent=b)
    _, parts = pymetis.part_graph(ranks, adjacency=graph, vweights=work.tolist())
    return np.asarray(parts)


def measure(rows, cols, work, part, ranks):
    """Largest and total ghosts, largest neighbour count, largest work over the mean."""
    cross = part[rows] != part[cols]
    ghost = np.unique(part[rows[cross]] * len(part) + cols[cross])
    owner = ghost // len(part)
    ghosts = np.bincount(owner, minlength=ranks)
    links = np.unique(owner * ranks + part[ghost % len(part)])
    neighbours = np.bincount(links // ranks, minlength=ranks)
    load = np.bincount(part, weights=work, minlength=ranks)
    return ghosts.max(), ghosts.sum(), neighbours.max(), load.max() / load.mean()


def main(cases):
    table = []
    for case in cases:
        model = peritherm.Model.from_case(case)
        rows, cols, work = body_graph(model)
        name = os.path.basename(case)
        for ranks in RANKS:
            if ranks > model.n_body // 50:
                continue
            for method, part in [("contiguous", contiguous(work, ranks)), ("METIS", metis(rows, cols, work, ranks))]:
                g_max, g_all, nbr, imbalance = measure(rows, cols, work, part, ranks)
                table.append([name, str(model.n_body), str(ranks), method, str(g_max), str(g_all), str(nbr), f"{imbalance:.3f}"])
                print(" | ".join(table[-1]), flush=True)
    columns = ["case", "body nodes", "ranks", "partition", "most ghosts", "ghosts in all", "most neighbour ranks", "most work / mean"]
    figure_file.write("partitioners", "python3 scripts/partitioners.py", columns, table)


if __name__ == "__main__":
    os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    main(sys.argv[1:] or CASES)
