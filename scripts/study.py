"""Runs `peritherm` commands for a study script and writes its figure file with the checks
that scripts/check-figures.sh reruns: each figure a row shows is read from a file the command
wrote (a number at a JSON pointer, or a whole field file by its hash), and the same reading is
recorded as a check. Run from the repository root; the binary is $PERITHERM or
target/release/peritherm (scripts/peritherm-bin.sh builds it)."""
import csv
import json
import os
import subprocess
import sys

import figure_file

# Relative tolerance of a figure that carries the built-in FEM's round-off, which depends on
# the order of its threaded assembly (far below 1e-6 of any figure a study tables).
FEM_REL_TOL = 1e-6


def fnv1a_hex(data):
    """FNV-1a, 64 bits, hexadecimal, as `peritherm_post::figures::fnv1a_hex`."""
    h = 0xCBF29CE484222325
    for b in data:
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}"


def pointer_get(doc, pointer):
    """The value at a JSON pointer (RFC 6901) of a parsed document."""
    for part in pointer.split("/")[1:]:
        part = part.replace("~1", "/").replace("~0", "~")
        doc = doc[int(part)] if isinstance(doc, list) else doc[part]
    return doc


class Study:
    """The rows and checks of one figure file."""

    def __init__(self, name, command, out):
        self.name, self.command, self.out = name, command, out
        self.bin = os.environ.get("PERITHERM", "target/release/peritherm")
        self.rows, self.checks, self.dirs = [], [], {}

    def run(self, args):
        """Runs `peritherm ARGS --out DIR` once per argument list; returns DIR."""
        key = tuple(args)
        if key not in self.dirs:
            out = os.path.join(self.out, f"{self.name}_{len(self.dirs)}")
            cmd = [self.bin, *args, "--out", out]
            print("+", " ".join(cmd), file=sys.stderr, flush=True)
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
            self.dirs[key] = out
        return self.dirs[key]

    def measure(self, args, file, pointer, rel_tol):
        """The number at `pointer` of `file` that `peritherm ARGS` writes, recorded as a
        check within `rel_tol`."""
        with open(os.path.join(self.run(args), file)) as f:
            value = float(pointer_get(json.load(f), pointer))
        self.checks.append({"kind": "measure", "args": list(args), "file": file,
                            "pointer": pointer, "value": value, "rel_tol": rel_tol})
        return value

    def file(self, args, file):
        """The path of `file` that `peritherm ARGS` writes, its bytes recorded as a check."""
        path = os.path.join(self.run(args), file)
        with open(path, "rb") as f:
            digest = fnv1a_hex(f.read())
        self.checks.append({"kind": "file", "args": list(args), "file": file, "fnv1a": digest})
        return path

    def fields(self, args):
        """(t, rows of the field CSV as dicts) at every output of `peritherm ARGS`, each field
        file's bytes recorded as a check."""
        with open(os.path.join(self.run(args), "run.json")) as f:
            summary = json.load(f)
        for t, name in zip(summary["output_times"], summary["fields"]):
            with open(self.file(args, name)) as f:
                yield t, list(csv.DictReader(f))

    def write(self, columns):
        """Writes validation/<name>.json."""
        figure_file.write(self.name, self.command, columns, self.rows, checks=self.checks)
