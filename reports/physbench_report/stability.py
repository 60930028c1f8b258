"""Stability maps: per scenario family swept over a parameter and the step (the stiff springs),
each engine variant's stability class at every (parameter, dt)."""
from __future__ import annotations

import pandas as pd

from .load import families_of


def has_stability(rows: pd.DataFrame) -> bool:
    """Whether any of these rows carries a stability class (empty cells read back as NaN)."""
    return "stability" in rows and rows["stability"].notna().any()


def stability_maps(results: pd.DataFrame, meta: dict) -> list[dict]:
    """One table per scenario family: engine/variant against (parameter, dt), each cell the run's
    stability class (stable, unstable, over-damped, exploded) or its status when it did not run."""
    families = families_of(meta)
    maps = []
    for family, members in families.items():
        names = [m[1] for m in members]
        if not has_stability(results[results["scenario"].isin(names)]):
            continue  # a family without stability classes is a scaling family (scaling_charts)
        members.sort(key=lambda m: m[0])
        columns = []  # (scenario, dt, parameter text, dt text)
        for parameter, name, info in members:
            for dt in sorted(info.get("sweep_dt", [info.get("dt")]), reverse=True):
                columns.append((name, dt, f"{parameter:g}", f"1/{1 / dt:.0f}"))
        rows = []
        for label in results[results["scenario"].isin([m[1] for m in members])]["label"].unique():
            cells = []
            for name, dt, _, _ in columns:
                hit = results[(results["scenario"] == name) & (results["label"] == label) &
                              ((results["dt"] - dt).abs() <= 1e-6 * dt)]
                if hit.empty:
                    cells.append(("", ""))
                    continue
                row = hit.iloc[0]
                stability = row.get("stability")
                text = stability if isinstance(stability, str) and stability else row["status"]
                cells.append((text, text.replace(" ", "-")))
            rows.append(dict(label=label, cells=cells))
        parameter_name = members[0][2].get("parameter_name", "parameter")
        description = members[0][2].get("question", "")
        maps.append(dict(name=family, parameter_name=parameter_name, description=description, columns=columns,
                         rows=rows, groups=[(f"{p:g}", sum(1 for c in columns if c[0] == n)) for p, n, _ in members]))
    return maps
