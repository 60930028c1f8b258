"""What every section shares: one hue an engine and one line style a variant on every chart,
number formatting, section anchors, and a plotly figure as a page fragment."""
from __future__ import annotations

import base64
import gzip
import html
import itertools
import math
import sys
from pathlib import Path

import pandas as pd
import plotly.graph_objects as go
import plotly.io
import plotly.offline

# plotly.js's partial bundle with the trace types the pages draw (scatter and bar), from npm beside
# the viewer's packages (scripts/setup.sh installs them): a quarter of the full bundle's bytes
PLOTLY_BASIC = Path(__file__).resolve().parents[1] / "viewer" / "node_modules" / "plotly.js-basic-dist-min" / "plotly-basic.min.js"


def plotly_js() -> str:
    """plotly.js for a page: the basic bundle at the version the plotly package writes figures for,
    or the package's full bundle (with a warning) when the basic one is not installed or differs."""
    version = plotly.offline.get_plotlyjs_version()
    if PLOTLY_BASIC.is_file():
        text = PLOTLY_BASIC.read_text(encoding="utf-8")
        if f" v{version}\n" in text[:200]:
            return text
        why = f"{PLOTLY_BASIC} is not plotly.js {version}, the version the plotly package writes for"
    else:
        why = f"{PLOTLY_BASIC} is missing (scripts/setup.sh installs it)"
    print(f"report: {why}; the page carries plotly's full bundle instead", file=sys.stderr)
    return plotly.offline.get_plotlyjs()


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


_figures = itertools.count(1)


def figure_html(fig: go.Figure, height: int = 420, top: int = 50) -> str:
    """The figure as a div for the page (top: the margin above the plot, room for a title): an
    empty div and the figure's JSON beside it, gzipped and in base64 (a third of its bytes), which
    the page's script (LAZY_CHARTS) draws when the div comes near the window, so a page of two
    hundred charts opens as fast as its first screen."""
    fig.update_layout(template=TEMPLATE, margin=dict(l=60, r=20, t=top, b=50), height=height,
                      legend=dict(font=dict(size=11)))
    name = f"chart-{next(_figures)}"
    spec = gzip.compress(plotly.io.to_json(fig, validate=False, pretty=False).encode(), compresslevel=9, mtime=0)
    return (f'<div id="{name}" class="plotly-graph-div chart-lazy" style="height:{height}px; width:100%;"></div>'
            f'<script type="text/plain" class="chart-spec" data-for="{name}">'
            f'{base64.b64encode(spec).decode()}</script>')


# the page's one script that draws the charts: each when it comes within two windows' height of
# the view (or at once where IntersectionObserver is missing); window.physbenchDrawCharts() draws
# every one now (the browser test, a reader who prints the page)
LAZY_CHARTS = """(() => {
  const spec = async (div) => {
    const text = document.querySelector(`script.chart-spec[data-for="${div.id}"]`).textContent;
    const bytes = Uint8Array.from(atob(text), (c) => c.charCodeAt(0));
    return JSON.parse(await new Response(new Blob([bytes]).stream().pipeThrough(new DecompressionStream('gzip'))).text());
  };
  const draw = async (div) => {
    if (div.dataset.drawn) return;
    div.dataset.drawn = '1';
    const { data, layout } = await spec(div);
    await Plotly.newPlot(div, data, layout, { displaylogo: false, responsive: true });
  };
  const charts = [...document.querySelectorAll('.chart-lazy')];
  window.physbenchDrawCharts = () => Promise.all(charts.map(draw));
  if (!('IntersectionObserver' in window)) return window.physbenchDrawCharts();
  const near = new IntersectionObserver((seen) => seen.forEach((e) => {
    if (e.isIntersecting) { near.unobserve(e.target); draw(e.target); }
  }), { rootMargin: '200% 0px' });
  charts.forEach((c) => near.observe(c));
  window.addEventListener('beforeprint', window.physbenchDrawCharts);
})();"""
