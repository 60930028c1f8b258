"""What every section shares: one hue an engine and one line style a variant on every chart,
number formatting, section anchors, and a plotly figure as a page fragment."""
from __future__ import annotations

import html
import math

import pandas as pd
import plotly.graph_objects as go
import plotly.offline

# one hue an engine and one line style and marker a variant, the same on every chart of a page
ENGINE_HUES = {"rtp": "#d62728", "bullet": "#1f77b4", "ode": "#2ca02c", "box2d": "#9467bd",
               "box2d-v3": "#8c564b", "mujoco": "#ff7f0e", "mujoco-2.2": "#bcbd22", "jolt": "#17becf",
               "rapier": "#e377c2", "test-fault": "#7f7f7f"}
SPARE_HUES = ["#393b79", "#637939", "#8c6d31", "#843c39", "#7b4173"]
DASHES = ["solid", "dash", "dot", "dashdot", "longdash", "longdashdot"]
SYMBOLS = ["circle", "square", "diamond", "triangle-up", "x", "star", "cross", "pentagon", "hexagon", "triangle-down"]
_variant_index: dict[str, int] = {}


def learn_styles(results: pd.DataFrame) -> None:
    """Each engine's variants (and knob-swept configurations) numbered in the order the results first
    name them, for the page."""
    _variant_index.clear()
    counts: dict[str, int] = {}
    for engine, label in zip(results["engine"], results["label"]):
        if label not in _variant_index:
            _variant_index[label] = counts.get(engine, 0)
            counts[engine] = _variant_index[label] + 1


def hue(engine: str) -> str:
    if engine in ENGINE_HUES:
        return ENGINE_HUES[engine]
    return SPARE_HUES[sum(map(ord, engine)) % len(SPARE_HUES)]


def trace_style(label: str) -> dict:
    """go.Scatter arguments: the engine's hue, the variant's dash and marker."""
    engine = label.split("/")[0]
    index = _variant_index.get(label, 0)
    return dict(line=dict(color=hue(engine), dash=DASHES[index % len(DASHES)]),
                marker=dict(color=hue(engine), symbol=SYMBOLS[index % len(SYMBOLS)]))


def fmt(value, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if isinstance(value, (int, float)):
        if value == 0:
            return "0"
        if abs(value) >= 1e5 or abs(value) < 1e-3:
            return f"{value:.{digits - 1}e}"
        return f"{value:.{digits}g}"
    return html.escape(str(value))


def anchor_of(name: str) -> str:
    return "s-" + "".join(c if c.isalnum() or c in "-_" else "-" for c in name)


def figure_html(fig: go.Figure, height: int = 420) -> str:
    fig.update_layout(template="plotly_white", margin=dict(l=60, r=20, t=50, b=50), height=height,
                      legend=dict(font=dict(size=11)))
    return plotly.offline.plot(fig, output_type="div", include_plotlyjs=False, config={"displaylogo": False})
