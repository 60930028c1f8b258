"""The first screen: the suite's key questions answered in pictures, one small chart a question, side
by side. Each draws cost against error with every engine's own Pareto front (a line through the
configurations of that engine that none of its others beats on both), one hue an engine, rtp
marked; only runs that passed count (contacts.passed). The benchmark programs' broad and narrow
phase, where the run has them, are drawn as cost per engine."""
from __future__ import annotations

import numpy as np
import pandas as pd
import plotly.graph_objects as go

from .contacts import DRIFT_FLOOR, passed
from .load import is_nominal
from .rounds import BASELINE_SUFFIXES
from .speed import headline_metric, pareto_front
from .style import figure_html, hue

# the questions in page order: the scenes that can answer each, the first one present with a run that
# passed answering it; kind: "stack" (drift against ms per step at the scene's own step), "error"
# (the headline error against wall s per simulated s over the step sweep), "throughput" (particle-steps/s)
KEY_QUESTIONS = [
    dict(topic="stacking", kind="stack",
         question="Which engine keeps a stack standing for the least time per step?",
         scenes=["pyramid-20", "tower-20", "pyramid-10", "tower-10", "pyramid-50", "many-pyramids", "pyramid-100"]),
    dict(topic="free motion", kind="error",
         question="Which engine follows a free body most accurately for the time it takes?",
         scenes=["tumbling-box", "symmetric-top", "projectile", "projectile-planar"]),
    dict(topic="springs", kind="error",
         question="Which engine follows a spring most accurately for the time it takes?",
         scenes=["spring-cube", "spring-oscillator", "spring-chain", "spring-oscillator-damped"]),
    dict(topic="particles", kind="error",
         question="Which engine keeps particles on their orbit most accurately for the time it takes?",
         scenes=["particles-orbit"]),
    dict(topic="particles", kind="throughput",
         question="Which engine moves the most particles per second?",
         scenes=["particles-attractors", "particles-snow", "particles-plume", "particles-attractors-planar",
                 "particles-plume-planar"]),
]
# a small chart's height and the room above its plot (rtp's name may sit over its top point)
HEIGHT, TOP = 270, 20


def one_thread(rows: pd.DataFrame) -> pd.DataFrame:
    """Every peer runs on one thread: rtp's two-thread variants take no part in a front. rtp
    compiled for the baseline instruction set (physbench-rtp-baseline) is a front of its own,
    rtp-x86-64: the equal-footing line beside the native build's."""
    rows = rows[~rows["variant"].str.endswith("-2t")].copy()
    for suffix in BASELINE_SUFFIXES:
        baseline = (rows["engine"] == "rtp") & rows["variant"].str.endswith(suffix)
        rows.loc[baseline, "engine"] = "rtp" + suffix
    return rows


def stack_points(rows: pd.DataFrame, meta: dict) -> pd.DataFrame:
    """The runs of a stack scene that passed, at its own step: cost in ms per step, error the max
    drift (m), drift under DRIFT_FLOOR at it (a log axis has no zero)."""
    own = rows[[is_nominal(meta, r) for _, r in rows.iterrows()]]
    ok = one_thread(own[passed(own)])
    ok = ok[ok["steps_per_s"].notna() & (ok["steps_per_s"] > 0) & ok["stack_drift_max"].notna()].copy()
    ok["cost"] = 1e3 / ok["steps_per_s"]
    ok["error"] = ok["stack_drift_max"].clip(lower=DRIFT_FLOOR)
    return ok


def error_points(rows: pd.DataFrame) -> tuple[pd.DataFrame, str]:
    """The runs of a scene with an error metric that passed, over its step sweep: cost in wall s
    per simulated s, error the headline metric's max (an exact 0 drawn at the least error drawn);
    and the metric's name."""
    metric = headline_metric(rows)
    if metric is None:
        return rows.iloc[0:0], ""
    column, title = metric
    ok = one_thread(rows[passed(rows)])
    ok = ok[ok["steps_per_s"].notna() & ok["wall_s_median"].notna() & ok[column].notna()].copy()
    ok["cost"] = ok["wall_s_median"] / ok["duration"]
    ok["error"] = ok[column].abs()
    positive = ok.loc[ok["error"] > 0, "error"]
    if not positive.empty:
        ok["error"] = ok["error"].clip(lower=positive.min())
    return ok, title.lower()


def engine_fronts(points: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """Each engine's own Pareto front of cost against error, cheapest first."""
    return {engine: pareto_front(mine, "error") for engine, mine in points.groupby("engine", sort=False)}


def rtp_last(engines) -> list[str]:
    """rtp drawn last, over its peers."""
    return sorted(engines, key=lambda e: e == "rtp")


def log_range(values) -> list[float]:
    """A log axis's range (log10 units) over these values, a decade at least, so that a chart of
    close values still has a decade's ticks, not a crowd of 1.61×10⁻⁴, 1.62×10⁻⁴, …"""
    logs = np.log10(np.asarray([v for v in values if v > 0], float))
    low, high = float(logs.min()), float(logs.max())
    middle, half = (low + high) / 2, max(0.5, (high - low) / 2 * 1.1)
    return [middle - half, middle + half]


def decade_ticks(span: float) -> dict:
    """Log axis ticks at whole decades, five at most: a small chart has no room for the 2s and 5s
    between them."""
    return dict(dtick=max(1, int(np.ceil(span / 5))), exponentformat="power", type="log")


def front_figure(fronts: dict[str, pd.DataFrame], x_title: str, y_title: str, cost_unit: str, error_unit: str) -> go.Figure:
    """One line per engine through its front, its hue; rtp's thick, starred and named."""
    fig = go.Figure()
    for engine in rtp_last(fronts):
        front = fronts[engine]
        mine = engine == "rtp"
        steps = [f"dt 1/{1 / dt:.0f} s" if pd.notna(dt) and dt > 0 else "" for dt in front["dt"]]
        fig.add_trace(go.Scatter(
            x=front["cost"], y=front["error"], mode="lines+markers+text" if mine else "lines+markers", name=engine,
            text=["rtp"] + [""] * (len(front) - 1) if mine else None, textposition="top right", cliponaxis=False,
            textfont=dict(color=hue(engine), size=13),
            line=dict(color=hue(engine), width=3.5 if mine else 1.5),
            marker=dict(color=hue(engine), size=11 if mine else 6, symbol="star" if mine else "circle"),
            customdata=list(zip(front["label"], steps)),
            hovertemplate=f"%{{customdata[0]}}, %{{customdata[1]}}<br>%{{x:.3g}} {cost_unit}"
                          f"<br>%{{y:.3g}} {error_unit}<extra></extra>"))
    fig.update_layout(showlegend=False)
    costs = [c for f in fronts.values() for c in f["cost"]]
    errors = [e for f in fronts.values() for e in f["error"]]
    x, y = log_range(costs), log_range(errors)
    fig.update_xaxes(title_text=x_title, title_font=dict(size=12), range=x, **decade_ticks(x[1] - x[0]))
    fig.update_yaxes(title_text=y_title, title_font=dict(size=12), range=y, **decade_ticks(y[1] - y[0]))
    return fig


def missing_note(rows: pd.DataFrame, points: pd.DataFrame) -> str:
    """The engines that ran the scene with no run on the chart: none of theirs passed."""
    absent = [e for e in rows["engine"].unique() if e not in set(points["engine"])
              and (rows.loc[rows["engine"] == e, "status"] != "unsupported").any()]
    return f"; no run passed: {', '.join(absent)}" if absent else ""


def stack_chart(name: str, rows: pd.DataFrame, meta: dict, question: dict) -> dict | None:
    points = stack_points(rows, meta)
    if points.empty:
        return None
    fig = front_figure(engine_fronts(points), "ms per step, median", "max drift (m)", "ms per step", "m drift")
    return dict(question=question["question"], topic=question["topic"], scene=name, engines=set(points["engine"]),
                chart=figure_html(fig, height=HEIGHT, top=TOP),
                note=f"{name} at its own step, runs that stand (drift under {DRIFT_FLOOR:g} m drawn at it)"
                     + missing_note(rows, points))


def scene_fronts_chart(rows: pd.DataFrame, meta: dict) -> str | None:
    """A stack scene's every engine's own front over all its configurations at the scene's own
    step (variants and swept knobs), drawn full width for the scene's section; None when no run
    passed."""
    points = stack_points(rows, meta)
    if points.empty:
        return None
    fig = front_figure(engine_fronts(points), "ms per step, median", "max drift (m)", "ms per step", "m drift")
    fig.update_layout(showlegend=True)
    return figure_html(fig, height=360, top=TOP)


def error_chart(name: str, rows: pd.DataFrame, question: dict) -> dict | None:
    points, metric = error_points(rows)
    if points.empty:
        return None
    unit = "rad" if "orientation" in metric else "m"
    fig = front_figure(engine_fronts(points), "wall s per simulated s", f"max {metric} ({unit})",
                       "s per simulated s", unit)
    steps = points["dt"].nunique()
    return dict(question=question["question"], topic=question["topic"], scene=name, engines=set(points["engine"]),
                chart=figure_html(fig, height=HEIGHT, top=TOP),
                note=f"{name}, {metric} over {steps} step{'s' if steps > 1 else ''}" + missing_note(rows, points))


def throughput_chart(name: str, rows: pd.DataFrame, meta: dict, question: dict) -> dict | None:
    """Each engine's most particle-steps per second over its runs that passed, as a bar."""
    own = rows[[is_nominal(meta, r) for _, r in rows.iterrows()]]
    ok = one_thread(own[passed(own)])
    ok = ok[ok["body_steps_per_s"].notna()]
    if ok.empty:
        return None
    best = ok.loc[ok.groupby("engine")["body_steps_per_s"].idxmax()].sort_values("body_steps_per_s")
    fig = go.Figure(go.Bar(
        x=best["body_steps_per_s"], y=best["engine"], orientation="h",
        marker=dict(color=[hue(e) for e in best["engine"]],
                    line=dict(color="black", width=[2 if e == "rtp" else 0 for e in best["engine"]])),
        customdata=best["label"], hovertemplate="%{customdata}<br>%{x:.3g} particle-steps/s<extra></extra>"))
    fig.update_layout(showlegend=False)
    x = log_range(best["body_steps_per_s"])
    x[0] = min(x[0], x[1] - 2)  # room for the slowest engine's bar
    fig.update_xaxes(title_text="particle-steps per s (more is faster)", title_font=dict(size=12), range=x,
                     **decade_ticks(x[1] - x[0]))
    return dict(question=question["question"], topic=question["topic"], scene=name, engines=set(best["engine"]),
                chart=figure_html(fig, height=HEIGHT, top=TOP),
                note=f"{name} at its own step, each engine's fastest run that passed" + missing_note(rows, best))


def broadphase_chart(broadphase: dict | None) -> dict | None:
    """µs per update against the box count, coherent motion, one line per broad phase."""
    rows = [r for r in (broadphase or {}).get("rows", []) if r["motion"] == "coherent" and "us" in r]
    if not rows:
        return None
    fig = go.Figure()
    engines = list(dict.fromkeys(r["engine"] for r in rows))
    for engine in sorted(engines, key=lambda e: e.startswith("rtp/")):
        points = sorted((r["boxes"], r["us"]) for r in rows if r["engine"] == engine)
        mine = engine.startswith("rtp/")
        fig.add_trace(go.Scatter(x=[b for b, _ in points], y=[u for _, u in points], mode="lines+markers",
                                 name=engine, line=dict(color=hue(engine.split("/")[0]), width=3.5 if mine else 1.5),
                                 marker=dict(color=hue(engine.split("/")[0]), symbol="star" if mine else "circle",
                                             size=11 if mine else 6),
                                 hovertemplate=f"{engine}<br>%{{x}} boxes<br>%{{y:.3g}} µs<extra></extra>"))
    fig.update_layout(showlegend=False)
    x, y = log_range([r["boxes"] for r in rows]), log_range([r["us"] for r in rows])
    fig.update_xaxes(title_text="boxes", title_font=dict(size=12), range=x, **decade_ticks(x[1] - x[0]))
    fig.update_yaxes(title_text="µs per update, median", title_font=dict(size=12), range=y,
                     **decade_ticks(y[1] - y[0]))
    return dict(question="Which broad phase updates its pairs in the least time as the boxes grow?",
                topic="broad phase", scene="broadphase_bench", engines={e.split("/")[0] for e in engines},
                chart=figure_html(fig, height=HEIGHT, top=TOP),
                note="broadphase_bench, coherent motion; every broad phase finds the exact pair set")


def narrowphase_chart(narrowphase: dict | None) -> dict | None:
    """ns per pair of each narrow phase on each pair set, a dot a (set, engine)."""
    rows = [r for r in (narrowphase or {}).get("rows", []) if "ns" in r]
    if not rows:
        return None
    fig = go.Figure()
    engines = list(dict.fromkeys(r["engine"] for r in rows))
    for engine in sorted(engines, key=lambda e: e.startswith("rtp/")):
        mine = [r for r in rows if r["engine"] == engine]
        rtp = engine.startswith("rtp/")
        fig.add_trace(go.Scatter(x=[r["ns"] for r in mine], y=[r["set"] for r in mine], mode="markers", name=engine,
                                 marker=dict(color=hue(engine.split("/")[0]), symbol="star" if rtp else "circle",
                                             size=12 if rtp else 8),
                                 hovertemplate=f"{engine}<br>%{{y}}<br>%{{x:.3g}} ns per pair<extra></extra>"))
    fig.update_layout(showlegend=False)
    x = log_range([r["ns"] for r in rows])
    fig.update_xaxes(title_text="ns per pair, median", title_font=dict(size=12), range=x, **decade_ticks(x[1] - x[0]))
    fig.update_yaxes(title_text="pair set", title_font=dict(size=12), automargin=True)
    return dict(question="Which narrow phase answers a pair of shapes in the least time?",
                topic="narrow phase", scene="narrowphase_bench", engines={e.split("/")[0] for e in engines},
                chart=figure_html(fig, height=HEIGHT, top=TOP),
                note="narrowphase_bench; agreement with rtp in the narrow phase section")


def first_screen(results: pd.DataFrame, meta: dict, broadphase: dict | None = None,
                 narrowphase: dict | None = None) -> dict | None:
    """The first screen's charts, a key question each, in KEY_QUESTIONS order (a topic answered
    once: the first of its questions with a scene that has a run that passed), then the broad and
    narrow phase; and the engines drawn, rtp first, for the key above them."""
    charts, answered = [], set()
    present = set(results["scenario"])
    for question in KEY_QUESTIONS:
        if question["topic"] in answered:
            continue
        for name in question["scenes"]:
            if name not in present:
                continue
            rows = results[results["scenario"] == name]
            if question["kind"] == "stack":
                chart = stack_chart(name, rows, meta, question) if "stack_drift_max" in rows else None
            elif question["kind"] == "error":
                chart = error_chart(name, rows, question)
            else:
                chart = throughput_chart(name, rows, meta, question) if "body_steps_per_s" in rows else None
            if chart is not None:
                charts.append(chart)
                answered.add(question["topic"])
                break
    charts += [c for c in (broadphase_chart(broadphase), narrowphase_chart(narrowphase)) if c is not None]
    if not charts:
        return None
    engines = sorted(set().union(*(c["engines"] for c in charts)), key=lambda e: (e != "rtp", e))
    return dict(charts=charts, engines=[dict(name=e, hue=hue(e)) for e in engines])

