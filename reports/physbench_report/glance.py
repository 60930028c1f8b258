"""The front page, "At a glance": per scenario the fastest and the most accurate engine, the
Pareto front, each engine's best error within an equal time budget, and every failure in words."""
from __future__ import annotations

import pandas as pd

from .contacts import FAILED_VERDICTS
from .load import is_nominal
from .speed import pareto_front
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


def at_a_glance(results: pd.DataFrame, meta: dict) -> list[dict]:
    """Per scenario, the front page's answers: which engine variant is fastest and which most accurate
    at the scene's own step, which runs are on the Pareto front of cost against error (over the step
    sweep), the best error each engine variant reaches within an equal time budget, and what failed,
    in words."""
    glance = []
    for name, rows in results.groupby("scenario", sort=False):
        # a run passed when it is ok and its contact verdict, where it has one, is not a failure
        # (collapsed, drifts, settles, sinks, …): only such runs are named fastest, most accurate or
        # on a front; the others are listed as failures, in words
        verdicts = rows["contact_verdict"] if "contact_verdict" in rows else pd.Series("", index=rows.index)
        failed_verdict = verdicts.isin(FAILED_VERDICTS)
        passed = rows[(rows["status"] == "ok") & ~failed_verdict]
        # a mask with the rows' index: an empty list would select no columns, not no rows
        nominal = passed[pd.Series([is_nominal(meta, r) for _, r in passed.iterrows()], index=passed.index, dtype=bool)]
        ok = nominal[nominal["steps_per_s"].notna()]
        entry = dict(name=name, anchor=anchor_of(name), fastest="", accurate="", metric="", front="", budget="",
                     budget_rows=[], failures=[], unsupported=int((rows["status"] == "unsupported").sum()))
        if not ok.empty:
            best = ok.loc[ok["steps_per_s"].idxmax()]
            entry["fastest"] = f"{best['label']} ({fmt(best['steps_per_s'])} steps/s)"
        metric = next(((c, t) for c, t in GLANCE_METRICS if c in rows and rows[c].notna().any()), None)
        if metric:
            column, title = metric
            entry["metric"] = title
            scored = ok[ok[column].notna()]
            if not scored.empty:
                best = scored.loc[scored[column].abs().idxmin()]
                entry["accurate"] = f"{best['label']} ({fmt(abs(best[column]))})"
            points = passed[passed["steps_per_s"].notna() & passed[column].notna()].copy()
            if not points.empty:
                points["cost"] = points["wall_s_median"] / points["duration"]
                points[column] = points[column].abs()
                front = pareto_front(points, column)
                entry["front"] = ", ".join(f"{r['label']} at 1/{1 / r['dt']:.0f} s" for _, r in front.iterrows())
                # equal time budget: the cheapest run of the costliest engine, so that every engine
                # has a run within it; each engine's best error (any variant, any step) at that cost
                cheapest = points.groupby("engine")["cost"].min()
                budget = cheapest.max()
                within = points[points["cost"] <= budget * (1 + 1e-9)]
                best_within = within.loc[within.groupby("engine")[column].idxmin()].sort_values(column)
                entry["budget"] = fmt(budget)
                entry["budget_rows"] = [dict(label=r["label"], error=fmt(r[column]), dt=f"1/{1 / r['dt']:.0f}")
                                        for _, r in best_within.iterrows()]
        for index, r in rows.iterrows():
            why = r["message"] if isinstance(r.get("message"), str) and r["message"] else "no reason given"
            if r["status"] in FAILED:
                entry["failures"].append(f"{r['label']} {FAILED[r['status']]} at dt = {fmt(r['dt'])} s: {why}")
            elif r["status"] == "ok" and failed_verdict[index]:
                entry["failures"].append(f"{r['label']} {verdicts[index]} at dt = {fmt(r['dt'])} s: {why}")
        glance.append(entry)
    return glance
