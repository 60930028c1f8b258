"""The full results table: every scenario at its own step, one row per engine variant (a family's
members are drawn as their stability map or scaling chart instead)."""
from __future__ import annotations

import pandas as pd

from .load import SERIES, is_nominal
from .scenarios import drawn_as_family
from .style import fmt


def reference_failed(row) -> str:
    """The status of the converged reference a row needed when that reference did not run
    ("timeout", "error", …), else "": such a row has no position or orientation error."""
    status = row.get("reference_status")
    return status if isinstance(status, str) and status and status != "ok" else ""


def results_table(results: pd.DataFrame, meta: dict) -> dict:
    """The table's error columns (each trajectory error series any row has, at its max) and one row
    per run at its scene's own step, family members left out."""
    present = [c for c, _, _, summary in SERIES if summary in results and results[summary].notna().any()]
    family = drawn_as_family(results, meta)
    nominal = results[[is_nominal(meta, r) and r["scenario"] not in family for _, r in results.iterrows()]]
    rows = []
    for _, r in nominal.iterrows():
        spread = ""
        if pd.notna(r["steps_per_s"]):
            spread = f"{fmt(r['steps_per_s_min'])}–{fmt(r['steps_per_s_max'])}"
        rows.append(dict(
            scenario=r["scenario"], label=r["label"], status=r["status"], dt=fmt(r.get("dt")),
            sps=fmt(r["steps_per_s"]), spread=spread, bsps=fmt(r.get("body_steps_per_s")),
            rtf=fmt(r.get("realtime_factor")),
            errors=[fmt(r.get(f"{c}_max")) for c in present],
            reference_failed=reference_failed(r),
            message=r["message"] if isinstance(r.get("message"), str) else ""))
    return dict(columns=[(c, f"{c.replace('_', ' ')} max") for c in present], rows=rows)
