"""The full results table, a section of its own linked from the front page: every scenario at its
own step, one row per engine variant (a family's members are drawn as their stability map or
scaling chart instead), sortable by a click on a column header and filtered by text, engine and
status in the page (reports/viewer/src/table.js)."""
from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from .load import SERIES, is_nominal
from .scenarios import drawn_as_family
from .style import anchor_of, fmt

TABLE_JS = Path(__file__).resolve().parents[1] / "viewer" / "dist" / "table.js"


def reference_failed(row) -> str:
    """The status of the converged reference a row needed when that reference did not run
    ("timeout", "error", …), else "": such a row has no position or orientation error."""
    status = row.get("reference_status")
    return status if isinstance(status, str) and status and status != "ok" else ""


def sort_value(value) -> str:
    """A number as the table's scripts sort it (data-sort: the full value, not the rounded text), or
    "" for an empty cell."""
    if value is None or not isinstance(value, (int, float)) or math.isnan(value):
        return ""
    return repr(float(value))


def results_table(results: pd.DataFrame, meta: dict) -> dict:
    """The full table: one row per run at its scene's own step, family members left out, with
    the engine and status it is filtered by; its error columns are each trajectory error series
    any row has, at its max. Each number cell is (text, value to sort by)."""
    present = [c for c, _, _, summary in SERIES if summary in results and results[summary].notna().any()]
    family = drawn_as_family(results, meta)
    nominal = results[[is_nominal(meta, r) and r["scenario"] not in family for _, r in results.iterrows()]]
    rows = []
    for _, r in nominal.iterrows():
        spread = ""
        if pd.notna(r["steps_per_s"]):
            spread = f"{fmt(r['steps_per_s_min'])}–{fmt(r['steps_per_s_max'])}"
        numbers = [(fmt(r.get("dt")), sort_value(r.get("dt"))),
                   (fmt(r["steps_per_s"]), sort_value(r["steps_per_s"])),
                   (spread, sort_value(r["steps_per_s_min"]) if spread else ""),
                   (fmt(r.get("body_steps_per_s")), sort_value(r.get("body_steps_per_s"))),
                   (fmt(r.get("realtime_factor")), sort_value(r.get("realtime_factor")))]
        numbers += [(fmt(r.get(f"{c}_max")), sort_value(r.get(f"{c}_max"))) for c in present]
        rows.append(dict(
            scenario=r["scenario"], anchor=anchor_of(r["scenario"]), label=r["label"], engine=r["engine"],
            status=r["status"], numbers=numbers, reference_failed=reference_failed(r),
            message=r["message"] if isinstance(r.get("message"), str) else ""))
    return dict(columns=["dt (s)", "steps/s (median)", "min–max", "body-steps/s", "real-time ×"]
                + [f"{c.replace('_', ' ')} max" for c in present], rows=rows,
                engines=list(dict.fromkeys(r["engine"] for r in rows)),
                statuses=list(dict.fromkeys(r["status"] for r in rows)))


def table_script() -> str | None:
    """The table's sorting and filters (reports/viewer/src/table.js with tablesort, bundled by
    scripts/setup.sh), or None when it is not built: the table is then shown as it is."""
    return TABLE_JS.read_text(encoding="utf-8") if TABLE_JS.is_file() else None
