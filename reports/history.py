#!/usr/bin/env python3
"""The nightly history: each run's rows kept small, compared with the run before it, and a page of
trends per scenario (docs/regression.md, "Nightly and history").

    python reports/history.py add results/20261203-020000 [--history history]   # exit 1: regression
    python reports/history.py report [--history history] [-o history/index.html]

An entry is history/<created>-<commit>/ with results.csv.gz and metadata.json.gz (no trajectories,
poses or scene files: those stay with the run's own folder, which a nightly job may delete), and
compare.txt, `physbench compare`'s verdict against the entry before it. `./bench.sh --nightly` runs
the suite, then `add`, then `report`, and exits with `add`'s code.
"""
from __future__ import annotations

import argparse
import html
import csv
import gzip
import json
import re
import statistics
import sys
from pathlib import Path

import plotly.graph_objects as go
import plotly.offline

import build_report
import compare
from physbench_report.style import plotly_js

# a row's main error: the first of these it has (the scenario's own question)
MAIN_ERROR = ["position_err_max", "orientation_err_max", "stack_drift_max", "apex_rel_err_max",
              "slide_accel_rel_err", "exchange_err", "energy_drift_max"]


class HistoryError(Exception):
    pass


def entries(history: Path) -> list[Path]:
    """The entries, oldest first (their names start with the run's UTC creation time)."""
    if not history.is_dir():
        return []
    return sorted(p for p in history.iterdir() if p.is_dir() and (p / "results.csv.gz").exists())


def read_entry_rows(entry: Path) -> dict[tuple, dict]:
    with gzip.open(entry / "results.csv.gz", "rt", newline="") as f:
        return {compare.row_key(r): r for r in csv.DictReader(f)}


def read_entry_metadata(entry: Path) -> dict:
    with gzip.open(entry / "metadata.json.gz", "rt") as f:
        return json.load(f)


def write_queryable(results: Path, metadata: dict, target: Path) -> None:
    """The run's rows as Parquet with the run's time and commit on each, so the whole history is one
    table to DuckDB or pandas (docs/regression.md, "Querying the history")."""
    import pandas as pd

    rows = pd.read_csv(results, dtype={"message": str, "trajectory": str})
    rows.insert(0, "run_created", metadata.get("created", ""))
    rows.insert(1, "run_commit", metadata.get("git_commit") or "")
    # no column statistics, dictionaries or Arrow schema blob: a night's rows, not a data lake (a
    # 24-row run's file 14 KB instead of 45)
    rows.to_parquet(target, index=False, compression="zstd", write_statistics=False,
                    use_dictionary=False, store_schema=False)


def add(run: Path, history: Path, **compare_options) -> tuple[Path, int]:
    """Stores the run as a new entry; returns it and compare's exit code against the one before."""
    if not (run / "results.csv").exists() or not (run / "metadata.json").exists():
        raise HistoryError(f"{run}: not a finished run (no results.csv or metadata.json)")
    metadata = json.loads((run / "metadata.json").read_text())
    created = re.sub(r"[^0-9TZ]", "", metadata.get("created", "")) or "unknown"
    commit = (metadata.get("git_commit") or "nocommit")[:10]
    history.mkdir(parents=True, exist_ok=True)
    before = entries(history)
    rows = (run / "results.csv").read_bytes()
    # two runs of one commit can start in the same second (shards, a fast suite): -2, -3, … after
    # the first; the same run twice is refused
    entry, n = history / f"{created}-{commit}", 1
    while entry.exists():
        if (entry / "results.csv.gz").exists() and gzip.decompress((entry / "results.csv.gz").read_bytes()) == rows:
            raise HistoryError(f"{run} is in the history already, as {entry}")
        n += 1
        entry = history / f"{created}-{commit}-{n}"
    partial = history / (entry.name + ".partial")
    partial.mkdir()
    # mtime 0: an entry's bytes depend on the run only
    with gzip.GzipFile(partial / "results.csv.gz", "wb", mtime=0) as out:
        out.write(rows)
    with gzip.GzipFile(partial / "metadata.json.gz", "wb", mtime=0) as out:
        out.write(json.dumps(metadata, separators=(",", ":")).encode())
    write_queryable(run / "results.csv", metadata, partial / "results.parquet")
    code = 0
    if before:
        result = compare.compare(read_entry_rows(before[-1]), compare.read_rows(run), **compare_options)
        text = compare.format_text(result, before[-1], entry)
        (partial / "compare.txt").write_text(text + "\n")
        print(text)
        code = 1 if result.regressions else 0
    else:
        (partial / "compare.txt").write_text("the first entry: nothing to compare with\n")
    partial.rename(entry)
    return entry, code


def relative_speed(rows: dict, key: tuple, groups: dict[tuple, list[tuple]]) -> float | None:
    """A row's fastest steps/s over the median of its scene step's other engines' fastest (a number
    that means the same on any machine, as far as the engines' relative speeds do)."""
    own = compare.fastest(rows[key])
    peers = [compare.fastest(rows[k]) for k in groups[(key[0], key[3])]
             if k[1] != key[1] and rows[k]["status"] == "ok"]
    peers = [p for p in peers if p]
    return own / statistics.median(peers) if own and peers else None


def main_error(row: dict) -> tuple[str, float] | None:
    for column in MAIN_ERROR:
        value = compare.number(row, column)
        if value is not None:
            return column, abs(value)
    return None


def report(history: Path, out: Path) -> int:
    runs = entries(history)
    if not runs:
        raise HistoryError(f"{history}: no entries (run `history.py add RUN` first)")
    table = [(e, read_entry_rows(e), read_entry_metadata(e)) for e in runs]
    labels = [f"{m.get('created', e.name)[:16]} {(m.get('git_commit') or '')[:8]}" for e, _, m in table]
    scenarios = sorted({k[0] for _, rows, _ in table for k in rows})
    grouped = [compare.by_scene_step(rows) for _, rows, _ in table]  # once an entry
    sections = []
    for scenario in scenarios:
        series: dict[str, dict] = {}
        for i, (_, rows, _) in enumerate(table):
            groups = grouped[i]
            for key, row in rows.items():
                if key[0] != scenario or row["status"] != "ok":
                    continue
                name = f"{compare.label(key)} dt {key[3]:.4g}"
                s = series.setdefault(name, {"speed": [None] * len(table), "error": [None] * len(table), "metric": None})
                s["speed"][i] = relative_speed(rows, key, groups)
                found = main_error(row)
                if found:
                    s["metric"] = found[0]
                    s["error"][i] = found[1]
        if not series:
            continue
        speed, error = go.Figure(), go.Figure()
        for name, s in sorted(series.items()):
            if any(v is not None for v in s["speed"]):
                speed.add_trace(go.Scatter(x=labels, y=s["speed"], name=name, mode="lines+markers"))
            if any(v is not None and v > 0 for v in s["error"]):
                error.add_trace(go.Scatter(x=labels, y=[v if v and v > 0 else None for v in s["error"]],
                                           name=f"{name} ({s['metric']})", mode="lines+markers"))
        speed.update_layout(title=f"{scenario}: fastest steps/s over the median of the scene's other engines",
                            yaxis_type="log", height=360, margin=dict(t=40, b=40))
        error.update_layout(title=f"{scenario}: main error (log)", yaxis_type="log", height=360,
                            margin=dict(t=40, b=40))
        divs = [plotly.offline.plot(f, output_type="div", include_plotlyjs=False, config={"displaylogo": False})
                for f in (speed, error) if f.data]
        sections.append((scenario, divs))
    latest = (runs[-1] / "compare.txt").read_text() if (runs[-1] / "compare.txt").exists() else ""
    total = sum(p.stat().st_size for e in runs for p in e.iterdir())
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>physbench history</title>",
        f"<script>{plotly_js()}</script>",
        "<style>body{font-family:sans-serif;margin:1em 2em}pre{background:#f4f4f4;padding:.5em;overflow-x:auto}</style>",
        "</head><body><h1>physbench: the history</h1>",
        f"<p>{len(runs)} runs, {total:,} bytes in all ({total // len(runs):,} a run on average), "
        f"from {labels[0]} to {labels[-1]}.</p>",
        "<h2>The latest run against the one before</h2><pre>" + html.escape(latest) + "</pre>",
        "<h2>Contents</h2><ul>" + "".join(f"<li><a href='#{build_report.anchor_of(s)}'>{html.escape(s)}</a></li>" for s, _ in sections) + "</ul>",
    ]
    for scenario, divs in sections:
        parts.append(f"<h2 id='{build_report.anchor_of(scenario)}'>{html.escape(scenario)}</h2>" + "".join(divs))
    parts.append("</body></html>")
    partial = out.with_name(out.name + ".partial")
    partial.write_text("\n".join(parts))
    partial.rename(out)
    return len(runs)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    add_p = sub.add_parser("add", help="store a run as the newest entry and compare it with the one before")
    add_p.add_argument("run", type=Path)
    add_p.add_argument("--history", type=Path, default=Path("history"))
    report_p = sub.add_parser("report", help="write the trends page")
    report_p.add_argument("--history", type=Path, default=Path("history"))
    report_p.add_argument("-o", "--out", type=Path)
    args = parser.parse_args(argv)
    try:
        if args.command == "add":
            entry, code = add(args.run, args.history)
            print(f"history: {entry}")
            return code
        out = args.out or args.history / "index.html"
        count = report(args.history, out)
        print(f"history: {count} runs, trends in {out}")
        return 0
    except (HistoryError, compare.CompareError) as e:
        print(f"history: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
