"""What every section shares: one hue an engine and one line style a variant on every chart,
number formatting, section anchors, and a plotly figure as a page fragment."""
from __future__ import annotations

import html
import math

import pandas as pd
import plotly.graph_objects as go
import plotly.io
import plotly.offline

# one hue an engine and one line style and marker a variant, the same on every chart of a page
ENGINE_HUES = {"rtp": "#d62728", "bullet": "#1f77b4", "ode": "#2ca02c", "box2d": "#9467bd",
               "box2d-v3": "#8c564b", "mujoco": "#ff7f0e", "mujoco-2.2": "#bcbd22", "jolt": "#17becf",
               "rapier": "#e377c2", "test-fault": "#7f7f7f", "rtp-x86-64": "#ff9896"}
SPARE_HUES = ["#393b79", "#637939", "#8c6d31", "#843c39", "#7b4173"]
DASHES = ["solid", "dash", "dot", "dashdot", "longdash", "longdashdot"]
SYMBOLS = ["circle", "square", "diamond", "triangle-up", "x", "star", "cross", "pentagon", "hexagon", "triangle-down"]
# each engine's default variant, in order of preference: the first of these a scene ran is the
# engine's one visible line on a chart over time (the others wait behind the legend)
DEFAULT_VARIANTS = {"rtp": ["soft-step", "rk4", "midpoint"], "bullet": ["float"], "ode": ["quickstep"],
                    "box2d": ["default"], "mujoco": ["euler"], "mujoco-2.2": ["euler"], "box2d-v3": ["default"],
                    "rapier": ["default"], "jolt": ["default"], "physx": ["pgs"], "box3d": ["default"]}
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


def default_labels(rows: pd.DataFrame) -> set[str]:
    """The label of each engine's default variant among these rows: the first DEFAULT_VARIANTS
    names that ran at the variant's own settings (not a knob sweep), else the engine's first row."""
    chosen: dict[str, tuple[int, str]] = {}
    for _, r in rows.iterrows():
        preferred = DEFAULT_VARIANTS.get(r["engine"], [])
        rank = preferred.index(r["variant"]) if r["variant"] in preferred else len(preferred)
        if r["label"] != f"{r['engine']}/{r['variant']}":
            rank = len(preferred) + 1  # a swept knob's row stands for its engine only when nothing else ran
        if r["engine"] not in chosen or rank < chosen[r["engine"]][0]:
            chosen[r["engine"]] = (rank, r["label"])
    return {label for _, label in chosen.values()}


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


def page_template() -> go.layout.Template:
    """plotly_white as far as the page's charts use it, scatter and bar traces on x-y axes: the
    whole template is 7 kB of JSON in every chart, most of it for trace types the page never draws."""
    white = plotly.io.templates["plotly_white"]
    unused = ("polar", "ternary", "coloraxis", "colorscale", "scene", "geo")
    return go.layout.Template(
        layout={k: v for k, v in white.layout.to_plotly_json().items() if k not in unused},
        data={k: v for k, v in white.data.to_plotly_json().items() if k in ("scatter", "bar")})


TEMPLATE = page_template()


def figure_html(fig: go.Figure, height: int = 420, top: int = 50) -> str:
    """The figure as a div for the page (top: the margin above the plot, room for a title)."""
    fig.update_layout(template=TEMPLATE, margin=dict(l=60, r=20, t=top, b=50), height=height,
                      legend=dict(font=dict(size=11)))
    return plotly.offline.plot(fig, output_type="div", include_plotlyjs=False, config={"displaylogo": False})
