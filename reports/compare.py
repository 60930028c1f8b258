"""Compares two results folders, OLD then NEW (`physbench compare OLD NEW`): per row, faster / slower /
more accurate / less accurate / broken / fixed / unchanged; exit code 1 when NEW regressed.

Rows are matched by scenario, engine, variant, step and a sweep's iterations and substeps. The tests
(docs/regression.md):
- accuracy: each error metric of the row (lower is better) changed by more than --accuracy-tolerance of
  the old value and more than --accuracy-floor in absolute terms. The metrics come from deterministic
  runs (a build gives the same trajectory every time), so any such change is the code's, not noise.
- speed: never raw steps/s across runs (machines differ, and these VMs drift by up to 2x within
  minutes), but against the peers measured in the same runs: the rows of the same scene and step, of
  the other engines (or of --against). Each row is taken at its fastest repeat (a repeat is slowed by
  whatever else the machine did meanwhile and never sped up, so the fastest is the least disturbed, as
  timeit takes the minimum). The peers' speed change is the median over those rows of new fastest /
  old fastest (docs/regression.md says why this and not one peer row). A row is slower when its own change over the peers' fell by more
  than --speed-threshold AND its repeats, scaled by the peers' change, differ from the old run's by the
  two-sided Mann–Whitney U test at --alpha (the test Google Benchmark's compare.py uses), so that noise
  within the repeats' spread is never called a change.
- status: ok (or diverged / exploded …) in OLD and a failure in NEW is broken; the reverse is fixed.
  The contact verdict (stands, drifts, …) is compared the same way.
"""
from __future__ import annotations

import argparse
import csv
import math
import statistics
import sys
from dataclasses import dataclass, field
from pathlib import Path

# error metrics, lower is better; an absolute value where the sign only says the direction
ERROR_METRICS = {
    "position_err_max": "position error",
    "orientation_err_max": "orientation error",
    "energy_drift_max": "energy drift",
    "linear_momentum_drift_max": "linear momentum drift",
    "angular_momentum_drift_max": "angular momentum drift",
    "stack_drift_max": "stack drift",
    "penetration_max": "penetration",
    "top_height_change": "top height change",
    "energy_added_max": "energy added",
    "rest_speed_rms": "speed at rest",
    "apex_rel_err_max": "apex error",
    "slide_accel_rel_err": "slide acceleration error",
    "exchange_err": "velocity exchange error",
    "escaped": "boxes escaped",
    "tunnelled": "tunnelled",
}
GOOD_STATUS = {"ok"}
# contact verdicts from best to worst (docs/metrics.md, "Contact")
VERDICT_RANK = {"stands": 0, "contained": 0, "settles": 1, "drifts": 2, "unsettled": 2, "slides": 2,
                "sinks": 3, "escaped": 3, "collapsed": 4, "exploded": 5}
REGRESSIONS = {"slower", "less accurate", "broken", "worse verdict"}


class CompareError(Exception):
    pass


def row_key(row: dict) -> tuple:
    """A row's identity: scenario, engine, variant, step, and a sweep's solver iterations and substeps
    ('' for the variant's own settings, as in a run from before those columns)."""
    return (row["scenario"], row["engine"], row["variant"], float(row["dt"]),
            row.get("iterations") or "", row.get("substeps") or "")


def label(key: tuple) -> str:
    """ENGINE/VARIANT, with a sweep's knobs: 'rtp/sequential-impulse iterations 8'."""
    knobs = [f"{name} {value}" for name, value in zip(("iterations", "substeps"), key[4:6]) if value]
    return " ".join([f"{key[1]}/{key[2]}", *knobs])


def read_rows(folder: Path) -> dict[tuple, dict]:
    csv_file = folder / "results.csv"
    if not csv_file.exists():
        raise CompareError(f"{folder}: no results.csv (not a results folder, or an unfinished run)")
    with open(csv_file, newline="") as f:
        reader = csv.DictReader(f)
        missing = {"scenario", "engine", "variant", "dt", "status"} - set(reader.fieldnames or [])
        if missing:
            raise CompareError(f"{csv_file}: no column(s) {', '.join(sorted(missing))}")
        rows = {}
        for row in reader:
            rows[row_key(row)] = row
    return rows


def number(row: dict, key: str) -> float | None:
    text = row.get(key, "")
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


@dataclass
class Change:
    key: tuple
    verdict: str  # faster, slower, more accurate, less accurate, broken, fixed, better/worse verdict
    detail: str


@dataclass
class Comparison:
    against: str
    matched: int = 0
    only_old: list = field(default_factory=list)
    only_new: list = field(default_factory=list)
    speed_compared: int = 0
    changes: list[Change] = field(default_factory=list)

    @property
    def regressions(self) -> list[Change]:
        return [c for c in self.changes if c.verdict in REGRESSIONS]


def repeats(row: dict) -> list[float]:
    """Each timed repeat's steps/s, as `physbench run` writes them."""
    values = []
    for text in row.get("steps_per_s_repeats", "").split(";"):
        try:
            value = float(text)
        except ValueError:
            continue
        if math.isfinite(value) and value > 0:
            values.append(value)
    return values


def fastest(row: dict) -> float | None:
    value = number(row, "steps_per_s_max")
    return value if value and value > 0 else None


def by_scene_step(rows: dict) -> dict[tuple, list[tuple]]:
    """Row keys grouped by (scenario, dt): a row's peers are its own scene step's rows."""
    groups: dict[tuple, list[tuple]] = {}
    for key in rows:
        groups.setdefault((key[0], key[3]), []).append(key)
    return groups


def named_by(key: tuple, against: str) -> bool:
    """Whether a row is of --against's ENGINE or ENGINE/VARIANT."""
    engine, _, variant = against.partition("/")
    return key[1] == engine and (not variant or key[2] == variant)


def peers_change(old: dict, new: dict, of: tuple, against: str | None,
                 groups: dict[tuple, list[tuple]]) -> tuple[float, int] | None:
    """(median of new/old fastest over the peer rows timed ok in both runs, how many) for the row `of`:
    the rows of the same scene and step, which ran seconds apart from it, of --against (ENGINE or
    ENGINE/VARIANT; its own engine's other variants too), else of every other engine. The machine's
    speed wanders over seconds, and a scene's jobs run one after another, so its own peers share its
    spell (docs/regression.md); the median sets aside a peer whose job ran in a slow process."""
    logs = []
    for key in groups.get((of[0], of[3]), []):
        if key == of or key not in new:
            continue
        peer = named_by(key, against) if against else key[1] != of[1]
        if not peer:
            continue
        x, y = fastest(old[key]), fastest(new[key])
        if x and y and old[key]["status"] in GOOD_STATUS and new[key]["status"] in GOOD_STATUS:
            logs.append(math.log(y / x))
    return (math.exp(statistics.median(logs)), len(logs)) if logs else None


def speed_change(a: dict, b: dict, peers: float, alpha: float) -> tuple[float, bool, str] | None:
    """(the row's change over the peers', whether its repeats differ beyond noise, how it was told)"""
    x, y = fastest(a), fastest(b)
    if not (x and y):
        return None
    change = y / x / peers - 1.0
    old, new = repeats(a), repeats(b)
    if min(len(old), len(new)) >= 3:
        from scipy.stats import mannwhitneyu

        p = mannwhitneyu(old, [v / peers for v in new], alternative="two-sided").pvalue
        return change, p < alpha, f"fastest {x:.3g} → {y:.3g} steps/s, Mann–Whitney p = {p:.2g}, {len(old)} and {len(new)} repeats"
    # an older physbench wrote no repeats: the ranges from the fastest and slowest must not overlap
    lo_a, lo_b = number(a, "steps_per_s_min"), number(b, "steps_per_s_min")
    if not (lo_a and lo_b):
        return None
    apart = y / peers < lo_a or lo_b / peers > x
    return change, apart, f"fastest {x:.3g} → {y:.3g} steps/s, ranges"


def compare(old: dict, new: dict, against: str | None = None, speed_threshold: float = 0.10,
            accuracy_tolerance: float = 0.05, accuracy_floor: float = 1e-9, alpha: float = 0.01) -> Comparison:
    if against and not any(named_by(k, against) for k in set(old) & set(new)):
        raise CompareError(f"--against {against}: no such engine variant in both runs")
    result = Comparison(against=against or "every other engine")
    groups = by_scene_step(old)

    result.only_old = sorted(set(old) - set(new))
    result.only_new = sorted(set(new) - set(old))
    for key in sorted(set(old) & set(new)):
        a, b = old[key], new[key]
        result.matched += 1
        good_a, good_b = a["status"] in GOOD_STATUS, b["status"] in GOOD_STATUS
        if good_a and not good_b:
            result.changes.append(Change(key, "broken", f"status {a['status']} → {b['status']}: {b.get('message', '')}"))
            continue
        if good_b and not good_a:
            result.changes.append(Change(key, "fixed", f"status {a['status']} → {b['status']}"))
            continue
        if not (good_a and good_b):
            continue
        va, vb = a.get("contact_verdict", ""), b.get("contact_verdict", "")
        if va in VERDICT_RANK and vb in VERDICT_RANK and VERDICT_RANK[va] != VERDICT_RANK[vb]:
            worse = VERDICT_RANK[vb] > VERDICT_RANK[va]
            result.changes.append(Change(key, "worse verdict" if worse else "better verdict", f"{va} → {vb}"))
        worse, better = [], []
        for column, name in ERROR_METRICS.items():
            x, y = number(a, column), number(b, column)
            if x is None or y is None:
                continue
            x, y = abs(x), abs(y)
            if abs(y - x) <= max(accuracy_floor, accuracy_tolerance * x):
                continue
            (worse if y > x else better).append(f"{name} {x:.3g} → {y:.3g}")
        if worse:
            result.changes.append(Change(key, "less accurate", "; ".join(worse)))
        if better:
            result.changes.append(Change(key, "more accurate", "; ".join(better)))
        peers = peers_change(old, new, key, against, groups)
        told = speed_change(a, b, peers[0], alpha) if peers else None
        if told:
            result.speed_compared += 1
            change, differs, how = told
            if differs and abs(change) > speed_threshold:
                result.changes.append(Change(
                    key, "slower" if change < 0 else "faster",
                    f"{change:+.0%} against {result.against} (whose {peers[1]} rows changed x{peers[0]:.3g}; {how})"))
    order = ["broken", "slower", "less accurate", "worse verdict", "fixed", "faster", "more accurate",
             "better verdict"]
    result.changes.sort(key=lambda c: (order.index(c.verdict), c.key))
    return result


def format_text(result: Comparison, old: Path, new: Path) -> str:
    lines = [f"compare {old} → {new}", f"rows matched: {result.matched}; speed as the ratio to {result.against}, "
             f"compared on {result.speed_compared} rows"]
    if result.only_old:
        lines.append(f"only in OLD: {len(result.only_old)} rows (e.g. {result.only_old[0][0]} {label(result.only_old[0])})")
    if result.only_new:
        lines.append(f"only in NEW: {len(result.only_new)} rows (e.g. {result.only_new[0][0]} {label(result.only_new[0])})")
    if not result.changes:
        lines.append("no change beyond the noise")
    else:
        width = max(len(f"{c.key[0]}  {label(c.key)}") for c in result.changes)
        for c in result.changes:
            where = f"{c.key[0]}  {label(c.key)}"
            lines.append(f"{c.verdict:<14} {where:<{width}}  dt {c.key[3]:.6g}  {c.detail}")
    regressions = len(result.regressions)
    lines.append(f"{regressions} regression(s)" if regressions else "no regression")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="physbench compare", description=__doc__.split("\n\n")[0])
    parser.add_argument("old", type=Path, help="the results folder compared against (the baseline)")
    parser.add_argument("new", type=Path, help="the results folder under test")
    parser.add_argument("--against", help="ENGINE[/VARIANT]: the peer rows whose speed change a row's is taken "
                        "relative to (default: every engine but the row's own)")
    parser.add_argument("--speed-threshold", type=float, default=0.10,
                        help="a speed change smaller than this share is never flagged (default 0.10: a "
                             "step that takes 15 %% longer is 13 %% slower)")
    parser.add_argument("--alpha", type=float, default=0.01,
                        help="the Mann–Whitney U test's significance level for a speed change (default 0.01)")
    parser.add_argument("--accuracy-tolerance", type=float, default=0.05,
                        help="an error metric must change by more than this share of its old value (default 0.05)")
    parser.add_argument("--accuracy-floor", type=float, default=1e-9,
                        help="… and by more than this in absolute terms (default 1e-9, round-off level)")
    args = parser.parse_args(argv)
    for name, value in (("--speed-threshold", args.speed_threshold), ("--alpha", args.alpha),
                        ("--accuracy-tolerance", args.accuracy_tolerance),
                        ("--accuracy-floor", args.accuracy_floor)):
        if not (value >= 0 and math.isfinite(value)):
            print(f"physbench compare: {name} {value}: must be a finite number ≥ 0", file=sys.stderr)
            return 2
    try:
        result = compare(read_rows(args.old), read_rows(args.new), args.against, args.speed_threshold,
                         args.accuracy_tolerance, args.accuracy_floor, args.alpha)
    except CompareError as e:
        print(f"physbench compare: {e}", file=sys.stderr)
        return 2
    print(format_text(result, args.old, args.new))
    return 1 if result.regressions else 0


if __name__ == "__main__":
    sys.exit(main())
