"""Prints the `--set` settings that shorten a bundled case to a hundredth of its first output
(at least three steps when the case fixes time.dt), one per line: the short runs of
scripts/fields-table.sh and scripts/mpi-check.sh."""
import sys
import tomllib

time = tomllib.load(open(sys.argv[1], "rb"))["time"]
end = time.get("outputs", [time["end"]])[0] / 100
print(f"time.end={end!r}")
print(f"time.outputs=[{end!r}]")
if "dt" in time and time["dt"] > end / 3:
    print(f"time.dt={end / 3!r}")
