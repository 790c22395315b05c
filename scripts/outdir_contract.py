"""The OUTDIR contract for the plot scripts: summary.json of a `scratchlight optimize` output
read, and its values looked up by the JSON pointers that src/io/OptimizeOutDir.h lists
(optimizeSummaryKeys(), "/compare/lamp/name"), which the scripts cannot include. The C++ readers
type the same keys in src/io/OptimizeSummary.h; tests/test_outdir.cpp checks that every pointer a
plot script names is listed there with the script among its readers.
"""
import json
import os

SUMMARY = "summary.json"


def read_summary(outdir):
    """OUTDIR/summary.json as a dict."""
    with open(os.path.join(outdir, SUMMARY)) as f:
        return json.load(f)


def at(summary, pointer, default=None):
    """The value at a JSON pointer the contract lists; `default` when it is absent or null."""
    v = summary
    for part in pointer.split("/")[1:]:
        if isinstance(v, dict) and part in v:
            v = v[part]
        elif isinstance(v, list) and part.isdigit() and int(part) < len(v):
            v = v[int(part)]
        else:
            return default
    return default if v is None else v
