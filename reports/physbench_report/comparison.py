"""The opening section of a report built with --compare OLD: `physbench compare OLD this-run`
(docs/regression.md)."""
from __future__ import annotations

from pathlib import Path

import compare  # reports/compare.py, the `physbench compare` command's Python side

from .load import ReportError
from .style import fmt


def comparison_section(old: Path | None, folder: Path) -> dict | None:
    """`physbench compare OLD this-run`, as a section (docs/regression.md)"""
    if old is None:
        return None
    try:
        result = compare.compare(compare.read_rows(old), compare.read_rows(folder))
    except compare.CompareError as exc:
        raise ReportError(f"--compare: {exc}") from exc
    css = {"broken": "error", "slower": "error", "less accurate": "error", "worse verdict": "error",
           "fixed": "stable", "faster": "stable", "more accurate": "stable", "better verdict": "stable"}
    return dict(old=str(old), matched=result.matched, against=result.against, speed_compared=result.speed_compared,
                method="fastest repeat over the same scene's peers, Mann–Whitney U on the repeats",
                regressions=len(result.regressions), only_old=len(result.only_old), only_new=len(result.only_new),
                changes=[dict(verdict=c.verdict, css=css.get(c.verdict, ""), scenario=c.key[0],
                              label=f"{c.key[1]}/{c.key[2]}", dt=fmt(c.key[3]), detail=c.detail)
                         for c in result.changes])
