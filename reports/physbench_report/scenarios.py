"""One section per scenario: its contact table, replay, error over time for every engine on one
chart (drift and penetration on contact scenes), error per body along a chain, throughput, and
speed against error with its Pareto front."""
from __future__ import annotations

from pathlib import Path

import pandas as pd
import plotly.graph_objects as go

from .contacts import contact_table, has_contact_metrics
from .load import SERIES, is_nominal, trajectories
from .speed import speed_error
from .style import anchor_of, figure_html, fmt, hue, trace_style


def error_over_time(rows: pd.DataFrame, series: dict, column: str, title: str, unit: str) -> str | None:
    """One error column of the trajectories (series: load.trajectories of these rows) over time,
    the worst probed body at each sample, one line per engine variant on a log axis."""
    fig = go.Figure()
    for index, row in rows.iterrows():
        if index not in series:
            continue
        traj = series[index]
        if column not in traj or traj[column].isna().all():
            continue
        per_time = traj.groupby("time", sort=True)[column].max()
        # a log axis cannot show zeros: exact values sit at the floor
        fig.add_trace(go.Scatter(x=per_time.index, y=per_time.clip(lower=1e-16).values, mode="lines",
                                 name=row["label"], **trace_style(row["label"])))
    if not fig.data:
        return None
    if column in ("stack_drift", "penetration"):
        axis = f"{title.split(':')[0].split(' (')[0].lower()} ({unit})"
    else:
        axis = f"{title.split(' ')[0].lower()} error ({unit})" if unit else "relative drift"
    fig.update_layout(title=title, xaxis_title="time (s)", yaxis_title=axis)
    fig.update_yaxes(type="log", exponentformat="power")
    return figure_html(fig)


def error_by_body(rows: pd.DataFrame, series: dict) -> str | None:
    """Max position error of each probed body over the run, against its index: how error grows
    along a chain. Only for scenes with more than one probed body and a reference."""
    fig = go.Figure()
    for index, row in rows.iterrows():
        if index not in series:
            continue
        traj = series[index]
        if "body_position_err" not in traj or traj["body"].nunique() < 2 or traj["body_position_err"].isna().all():
            continue
        per_body = traj.groupby("body", sort=True)["body_position_err"].max()
        fig.add_trace(go.Scatter(x=per_body.index, y=per_body.clip(lower=1e-16).values, mode="lines+markers",
                                 name=row["label"], **trace_style(row["label"])))
    if not fig.data:
        return None
    fig.update_layout(title="Max position error of each body (body index along the scene)",
                      xaxis_title="body", yaxis_title="max position error (m)")
    fig.update_yaxes(type="log", exponentformat="power")
    return figure_html(fig)


def throughput_chart(rows: pd.DataFrame) -> str | None:
    ok = rows[rows["steps_per_s"].notna()]
    if ok.empty:
        return None
    fig = go.Figure(go.Bar(
        x=ok["label"], y=ok["steps_per_s"],
        error_y=dict(type="data", symmetric=False,
                     array=(ok["steps_per_s_max"] - ok["steps_per_s"]).clip(lower=0),
                     arrayminus=(ok["steps_per_s"] - ok["steps_per_s_min"]).clip(lower=0)),
        text=[fmt(v) for v in ok["steps_per_s"]], textposition="outside",
        marker_color=[hue(e) for e in ok["engine"]]))
    fig.update_layout(title="Throughput: median steps/s (bars: min to max over repeats)", yaxis_title="steps/s")
    fig.update_yaxes(type="log", exponentformat="power")
    return figure_html(fig)


def drawn_as_family(results: pd.DataFrame, meta: dict) -> set[str]:
    """The scenarios drawn as their family's stability map or scaling chart, without a section or
    table rows of their own; a contact family (the pyramids) keeps its sections: its drift and
    penetration are the question."""
    return {n for n, i in meta.get("scenarios", {}).items()
            if i.get("family") and not has_contact_metrics(results[results["scenario"] == n])}


def reference_error(info: dict) -> float | None:
    """The converged reference's own error (its change when its step is halved again), the largest
    over the steps it ran at; None for other references."""
    self_errors = info.get("reference_self_error")
    if isinstance(self_errors, dict):
        values = [v for v in self_errors.values() if isinstance(v, (int, float))]
        return max(values) if values else None
    return self_errors if isinstance(self_errors, (int, float)) else None


def scenario_sections(folder: Path, results: pd.DataFrame, meta: dict, replays: dict) -> list[dict]:
    """Each scenario's section but the family members', in the order of results.csv: its
    description, reference, contact table, replay (replays: replay.replays) and charts, the
    charts over time drawn at the scene's own step, speed against error over the whole sweep."""
    family = drawn_as_family(results, meta)
    sections = []
    for name, rows in results.groupby("scenario", sort=False):
        info = meta.get("scenarios", {}).get(name, {})
        if name in family:
            continue
        own = rows[[is_nominal(meta, r) for _, r in rows.iterrows()]]
        series = trajectories(folder, own)
        charts = [error_over_time(own, series, column, title, unit) for column, title, unit, summary in SERIES
                  if summary in own and own[summary].notna().any()]
        charts += [error_by_body(own, series), throughput_chart(own)]
        del series  # the next scenario's trajectories take their place
        self_errors = info.get("reference_self_error")
        floors = {float(k): v for k, v in self_errors.items()} if isinstance(self_errors, dict) else None
        chart, front = speed_error(rows, floors)
        charts.append(chart)
        self_error = reference_error(info)
        sweep = sorted(info.get("sweep_dt", []))
        sections.append(dict(
            name=name, anchor=anchor_of(name), description=info.get("description", ""), question=info.get("question", ""),
            dt=fmt(info.get("dt")), duration=fmt(info.get("duration")), reference=info.get("reference", ""),
            self_error=fmt(self_error) if self_error is not None else "",
            reference_failures=[dict(dt=fmt(float(dt)), why=why)
                                for dt, why in (info.get("reference_failure") or {}).items()],
            sweep=", ".join(f"1/{1 / dt:.0f}" for dt in sweep) if len(sweep) > 1 else "",
            charts=[c for c in charts if c], front=front, contact=contact_table(own), replay=replays.get(name),
            unsupported=[f"{r['label']}: {r['message']}" for _, r in own.iterrows() if r["status"] == "unsupported"]))
    return sections
