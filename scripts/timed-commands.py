#!/usr/bin/env python3
"""Times shell commands and writes the table as the figure file validation/<NAME>.json (the
docs show it; run scripts/update-docs.sh after this): per command, the median wall time of
--repeat runs and the peak resident set of its largest process (the kernel's rusage of the
command and every process it waited for: with mpiexec, the largest rank).

Usage: python3 scripts/timed-commands.py NAME [--repeat N] [--by CMD] [--label L] -- CMD [CMD ...]
Each CMD runs through bash from the repository root; a command that fails ends the script
with its exit status and writes nothing. --by is the command recorded as having measured the
table (default: this script's own command line); --label, given once per CMD, replaces the
command in the table's first column.
"""
import argparse
import os
import statistics
import subprocess
import sys
import time

import figure_file


def run(cmd):
    """Wall seconds and peak resident bytes of `cmd`'s largest process."""
    start = time.monotonic()
    child = subprocess.Popen(["bash", "-c", cmd], stdout=subprocess.DEVNULL, close_fds=False)
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.monotonic() - start
    code = os.waitstatus_to_exitcode(status)
    if code != 0:
        sys.exit(f"timed-commands: `{cmd}` failed with exit status {code}")
    return wall, usage.ru_maxrss * 1024


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("name")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--by")
    parser.add_argument("--label", action="append", default=[])
    parser.add_argument("commands", nargs="+")
    args = parser.parse_args()
    if args.label and len(args.label) != len(args.commands):
        sys.exit("timed-commands: give one --label per command, or none")
    labels = args.label or [f"`{c}`" for c in args.commands]
    rows = []
    for label, cmd in zip(labels, args.commands):
        runs = [run(cmd) for _ in range(args.repeat)]
        wall = statistics.median(w for w, _ in runs)
        peak = max(p for _, p in runs)
        rows.append([label, f"{wall:.1f}", f"{peak / 1e9:.2f}"])
        print(" | ".join(rows[-1]), flush=True)
    repeat = f"median of {args.repeat} runs" if args.repeat > 1 else "one run"
    columns = ["command", f"wall time (s, {repeat})", "peak resident of the largest process (GB)"]
    by = args.by or "python3 scripts/timed-commands.py " + " ".join(sys.argv[1:])
    figure_file.write(args.name, by, columns, rows)


if __name__ == "__main__":
    os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    main()
