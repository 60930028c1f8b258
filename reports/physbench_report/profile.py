"""Where a step's time goes: engines that time their own stages (rtp's StepProfile) write each
row's ms per step by stage into stage_ms, the stages named in metadata.json (engines.<engine>.stages).
Drawn for each such engine: its default variant over the scenarios, and every variant on the
scenario with the most bodies; the shares in a table."""
from __future__ import annotations

import pandas as pd
import plotly.graph_objects as go

from .load import is_nominal, is_swept
from .style import figure_html, fmt

# one colour a stage, the same on every chart (plotly's qualitative "Safe" and "Vivid" sets)
STAGE_COLOURS = ["#88CCEE", "#CC6677", "#DDCC77", "#117733", "#332288", "#AA4499", "#44AA99",
                 "#999933", "#882255", "#661100", "#6699CC", "#888888"]


def parse_stages(text) -> list[float] | None:
    """stage_ms as numbers, or None when the row has none (an engine that does not time stages)."""
    if not isinstance(text, str) or not text:
        return None
    return [float(part) if part else float("nan") for part in text.split(";")]


def stacked_bars(title: str, labels: list[str], stages: list[str], values: list[list[float]]) -> str:
    fig = go.Figure()
    for k, stage in enumerate(stages):
        fig.add_trace(go.Bar(name=stage, y=labels, x=[v[k] for v in values], orientation="h",
                             marker_color=STAGE_COLOURS[k % len(STAGE_COLOURS)]))
    fig.update_layout(barmode="stack", title=title, xaxis_title="ms per step",
                      yaxis=dict(autorange="reversed"))
    return figure_html(fig, height=max(260, 100 + 40 * len(labels)))


def stage_profiles(results: pd.DataFrame, meta: dict) -> list[dict]:
    """Per engine that times its stages: two charts and a table of every row's shares."""
    if "stage_ms" not in results:
        return []
    sections = []
    for engine, info in meta.get("engines", {}).items():
        stages = (info or {}).get("stages")
        if not stages:
            continue
        rows = results[(results["engine"] == engine) & (results["status"] == "ok")]
        rows = rows[[is_nominal(meta, r) and not is_swept(r) and parse_stages(r["stage_ms"]) is not None for _, r in rows.iterrows()]]
        if rows.empty:
            continue
        parsed = {i: parse_stages(r["stage_ms"]) for i, r in rows.iterrows()}
        if any(len(v) != len(stages) for v in parsed.values()):
            continue  # a row of another build's stage list: not drawn against these names
        default = rows.iloc[0]["variant"]  # rows are in plan order: an engine's default variant first
        first = rows[rows["variant"] == default]
        charts = [stacked_bars(f"{engine}/{default}: ms per step by stage, each scenario at its own step",
                               list(first["scenario"]), stages, [parsed[i] for i in first.index])]
        largest = rows.loc[rows["bodies"].idxmax(), "scenario"]
        variants = rows[rows["scenario"] == largest]
        if len(variants) > 1:
            charts.append(stacked_bars(f"{largest} ({int(variants.iloc[0]['bodies'])} bodies): every {engine} variant",
                                       list(variants["variant"]), stages, [parsed[i] for i in variants.index]))
        table = []
        for i, r in rows.iterrows():
            values = parsed[i]
            total = sum(v for v in values if v == v)
            step_ms = 1e3 / r["steps_per_s"] if r.get("steps_per_s", 0) > 0 else float("nan")
            table.append(dict(scenario=r["scenario"], variant=r["variant"], total=fmt(total),
                              step=fmt(step_ms),
                              shares=[f"{100 * v / total:.0f}" if total > 0 and v == v else "" for v in values]))
        sections.append(dict(engine=engine, stages=stages, charts=charts, table=table))
    return sections
