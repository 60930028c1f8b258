#!/usr/bin/env python3
"""Build one self-contained HTML report (index.html) from a physbench results folder.

Reads only files: results.csv, metadata.json, trajectories/*.csv (or *.parquet: reports/compact.py), scenes/*.json and poses/*.bin,
as `physbench run` writes them. The page embeds plotly.js, the replay viewer and the results
table's script (bundled by scripts/setup.sh into reports/viewer/dist), so it opens offline. The
report itself is the package physbench_report/ beside this file: a module a section, its
templates in physbench_report/templates/.

    python reports/build_report.py results/20261122-041500
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

# what other report modules and the tests use from here (history.py links with anchor_of)
from physbench_report.load import SCHEMA_FILE, ReportError
from physbench_report.page import build_report
from physbench_report.style import anchor_of, fmt

__all__ = ["ReportError", "SCHEMA_FILE", "anchor_of", "build_report", "fmt", "main"]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path, help="a results folder written by `physbench run`")
    parser.add_argument("--compare", type=Path, metavar="OLD",
                        help="an earlier results folder: the page opens with what changed since (physbench compare)")
    args = parser.parse_args(argv)
    try:
        out = build_report(args.results, args.compare)
    except ReportError as exc:
        print(f"build_report: {exc}", file=sys.stderr)
        return 2
    print(f"report: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
