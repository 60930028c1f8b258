"""The scoreboard, "At a glance": per scenario the fastest run that passed, the most accurate, and
what failed, in a few words (the charts of the first screen, front.py, come before it)."""
from __future__ import annotations

import pandas as pd

from .contacts import passed
from .load import is_nominal
from .style import anchor_of, fmt

# the error a scenario's question is about, in this order of preference (results.csv column, words)
GLANCE_METRICS = [("position_err_max", "position error"), ("orientation_err_max", "orientation error"),
                  ("apex_rel_err_max", "apex error"), ("slide_accel_rel_err", "slide acceleration error"),
                  ("exchange_err", "velocity exchange error"), ("roll_speed_rel_err", "rolling speed error"),
                  ("stack_drift_max", "stack drift"),
                  ("penetration_max", "deepest penetration"), ("energy_drift_max", "energy drift")]
# a failed run's status in words
FAILED = {"exploded": "exploded", "crashed": "crashed", "timeout": "timed out", "error": "failed",
          "diverged": "diverged"}


def failures_in_words(rows: pd.DataFrame, ok: pd.Series) -> list[dict]:
    """Each run that failed, one entry per engine variant and way of failing: "bullet/float
    collapsed", with the steps it did so at when the scenario was swept over several; why (the
    runs' messages) for a tooltip."""
    swept = rows["dt"].nunique() > 1
    grouped: dict[tuple, list] = {}
    for index, r in rows.iterrows():
        if r["status"] in FAILED:
            what = FAILED[r["status"]]
        elif r["status"] == "ok" and not ok[index]:
            what = r["contact_verdict"]
        else:
            continue
        grouped.setdefault((r["label"], what), []).append(r)
    failures = []
    for (label, what), failed in grouped.items():
        at = f" at dt = {', '.join(fmt(r['dt']) for r in failed)} s" if swept else ""
        why = "; ".join(dict.fromkeys(r["message"] for r in failed if isinstance(r.get("message"), str) and r["message"]))
        failures.append(dict(text=f"{label} {what}{at}", why=why or "no reason given"))
    return failures


def at_a_glance(results: pd.DataFrame, meta: dict) -> list[dict]:
    """Per scenario, the scoreboard's row: the fastest and the most accurate engine variant at the
    scene's own step among the runs that passed (ok, and no failing contact verdict), and every
    run that failed, in words."""
    glance = []
    for name, rows in results.groupby("scenario", sort=False):
        ok = passed(rows)
        good = rows[ok]
        # a mask with the rows' index: an empty list would select no columns, not no rows
        nominal = good[pd.Series([is_nominal(meta, r) for _, r in good.iterrows()], index=good.index, dtype=bool)]
        timed = nominal[nominal["steps_per_s"].notna()]
        entry = dict(name=name, anchor=anchor_of(name), fastest="", accurate="", metric="",
                     failures=failures_in_words(rows, ok), unsupported=int((rows["status"] == "unsupported").sum()))
        if not timed.empty:
            best = timed.loc[timed["steps_per_s"].idxmax()]
            entry["fastest"] = f"{best['label']} ({fmt(best['steps_per_s'])} steps/s)"
        metric = next(((c, t) for c, t in GLANCE_METRICS if c in rows and rows[c].notna().any()), None)
        if metric:
            column, title = metric
            entry["metric"] = title
            scored = timed[timed[column].notna()]
            if not scored.empty:
                best = scored.loc[scored[column].abs().idxmin()]
                entry["accurate"] = f"{best['label']} ({fmt(abs(best[column]))})"
        glance.append(entry)
    return glance
