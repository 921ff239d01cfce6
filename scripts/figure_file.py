"""Writes a figure file of validation/ (the format `peritherm table --json` writes and
scripts/update-docs.sh renders into the docs) from a script: the table, the command that
measured it, and the commit and machine it was measured on."""
import datetime
import json
import os
import subprocess


def provenance(threads=None):
    """Commit (with +changes when files outside validation/ differ from it), date, CPU,
    threads and load, as `peritherm::figures::provenance` records them."""
    git = ["git", "rev-parse", "--short=12", "HEAD"]
    commit = subprocess.run(git, capture_output=True, text=True).stdout.strip()
    pathspec = [":/", ":(top,exclude)validation"]
    dirty = subprocess.run(["git", "diff", "--quiet", "HEAD", "--"] + pathspec).returncode != 0
    machine = "unknown"
    for line in open("/proc/cpuinfo"):
        if line.startswith("model name"):
            machine = line.split(":", 1)[1].strip()
            break
    return {
        "commit": commit + ("+changes" if dirty else ""),
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d"),
        "machine": machine,
        "threads": threads or os.cpu_count(),
        "load": round(os.getloadavg()[0], 2),
    }


def write(name, command, columns, rows, threads=None, checks=None, source=None):
    """Writes validation/<name>.json (run from the repository root); `checks` are what
    scripts/check-figures.sh reruns (scripts/study.py makes them), none by default; `source`
    is the provenance of figures read from another figure file (default: this run's)."""
    figures = {
        "name": name,
        "command": command,
        "provenance": source or provenance(threads),
        "columns": columns,
        "rows": rows,
        "checks": checks or [],
    }
    tmp = f"validation/{name}.json.tmp"
    with open(tmp, "w") as f:
        f.write(json.dumps(figures, indent=2, ensure_ascii=False) + "\n")
    os.replace(tmp, f"validation/{name}.json")
