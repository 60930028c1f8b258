#!/usr/bin/env python3
"""A committed run summary (docs/runs/*.md): what the README and docs quote, with its source — the
command, the commit, the machine and the build of each run — and, per stack scenario, each engine
at its defaults and at its best knobs (the report's "Each engine at its best knobs" table), not the
whole results folder.

    .venv/bin/python reports/run_summary.py results/A [results/B …] --title "…" -o docs/runs/X.md
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from physbench_report.contacts import best_configurations  # noqa: E402
from physbench_report.load import ReportError, is_nominal, load_results  # noqa: E402
from physbench_report.rounds import PairedRatios, load_rounds  # noqa: E402


# the closed-form contact scenes' measures, in this order where a scenario has them
CLOSED_FORM_COLUMNS = [("apex_rel_err_max", "apex error max"), ("roll_speed_rel_err", "rolling speed error"),
                       ("roll_time_rel_err", "rolling time error"), ("energy_change_final", "energy change (final)"),
                       ("linear_momentum_drift_max", "momentum drift max"),
                       ("angular_momentum_drift_max", "angular momentum drift max"), ("cradle_answer", "cradle answer")]


def number(value) -> str:
    if isinstance(value, str):
        return value
    if value is None or pd.isna(value):
        return ""
    return f"{value:.3g}"


def verdict_tables(results: pd.DataFrame) -> list[str]:
    """Per contact scenario without a stack's drift: every row's status, verdict and measures."""
    lines = []
    for name, rows in results.groupby("scenario", sort=False):
        if "stack_drift_max" in rows and rows["stack_drift_max"].notna().any():
            continue
        if "contact_verdict" not in rows or rows["contact_verdict"].isna().all():
            continue
        columns = [(c, t) for c, t in CLOSED_FORM_COLUMNS if c in rows and rows[c].notna().any()]
        lines += [f"## {name}", "", "| engine / variant | status | verdict | " +
                  " | ".join(t for _, t in columns) + " | ms per step |",
                  "|---" * (4 + len(columns)) + "|"]
        for _, r in rows.iterrows():
            verdict = r["contact_verdict"] if isinstance(r["contact_verdict"], str) else ""
            ms = 1e3 / r["steps_per_s"] if pd.notna(r.get("steps_per_s")) and r["steps_per_s"] > 0 else None
            lines.append(f"| {r['label']} | {r['status']} | {verdict} | " +
                         " | ".join(number(r[c]) for c, _ in columns) + f" | {number(ms)} |")
        lines.append("")
    return lines


def summary(folders: list[Path], title: str) -> str:
    lines = [f"# {title}", ""]
    tables, closed_form = [], []
    for folder in folders:
        results, meta = load_results(folder)
        machine = meta.get("machine", {})
        lines += [f"- `{meta.get('command', '?')}`", f"  - commit {meta.get('git_commit', '?')}, "
                  f"{meta.get('created', '?')}; {meta.get('build', '?')} ({meta.get('compiler', '?')}); "
                  f"{machine.get('cpu', '?')}, {machine.get('logical_cores', '?')} logical cores, "
                  f"{machine.get('memory_gib', '?')} GiB, {machine.get('os', '?')}"]
        nominal = results[[is_nominal(meta, r) for _, r in results.iterrows()]]
        tables += best_configurations(nominal, PairedRatios(load_rounds(folder)))
        closed_form += verdict_tables(nominal)
    if not tables:
        return "\n".join(lines + [""] + closed_form)
    lines += ["", "Each engine's rows: its default variant at its own settings, and every configuration it ran "
              "(variants, and each swept substep count), one thread each (rtp's two-thread variants are left "
              "out). \"Cheapest that stands\" is the fastest whose verdict is "
              "`stands`; \"rtp faster ×\" its ms per step over rtp's cheapest standing configuration's (below 1: "
              "rtp is slower), and \"rtp-x86-64 faster ×\", where the run has it, the same against rtp compiled "
              "for the baseline instruction set, as the peers' generic builds are; \"least drift\" is the least drift "
              "within the ms per step of rtp's default; \"at no worse accuracy\" reads every "
              "configuration of a peer, standing or not, against rtp's cheapest configuration as accurate on every "
              "measure (a verdict no lower; drift, the top's height change and the final penetration no larger): "
              "the least of the peer's ms per step over rtp's, the peer's best showing, with the two configurations "
              "it compares, and any peer configuration no rtp configuration matches. A "
              "scene step's jobs were timed in interleaved rounds (docs/metrics.md, \"Interleaved timing\"): a "
              "ratio with an interval is the median of its per-round ratios with their bootstrap 95 % interval; "
              "one without comes from jobs timed in one round only (a run over 3 s) or a run from before "
              "rounds: one run's ratio, on a machine whose speed drifts.", ""]
    for t in tables:
        base = t.get("baseline")
        lines += [f"## {t['scenario']} (rtp's default {t['rtp_ms']} ms per step)", "",
                  "| engine | its defaults | cheapest that stands | ms per step | drift max (m) | rtp faster × "
                  + (f"| {base} faster × " if base else "") + "| least drift within rtp's default ms "
                  "| rtp faster × at no worse accuracy " + (f"| {base} faster × at no worse accuracy " if base else "")
                  + "|", "|---|---|---|---|---|---|---|---|" + ("---|---|" if base else "")]
        for r in t["rows"]:
            lines.append(f"| {r['engine']} | {r['default']} | {r['best']} | {r['best_ms']} | {r['best_drift']} "
                         f"| {r['ratio']} " + (f"| {r['ratio_baseline']} " if base else "") + f"| {r['within']} "
                         f"| {r['matched']} " + (f"| {r['matched_baseline']} " if base else "") + "|")
        lines.append("")
    return "\n".join(lines + closed_form)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--title", required=True)
    parser.add_argument("-o", "--out", type=Path, required=True)
    args = parser.parse_args()
    try:
        text = summary(args.folders, args.title)
    except ReportError as e:
        print(f"run_summary: {e}", file=sys.stderr)
        return 2
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text + "\n", encoding="utf-8")
    print(f"run_summary: {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
