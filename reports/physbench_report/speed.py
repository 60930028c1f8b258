"""Speed against error: the headline error against cost over a scenario's step sweep, each curve's
measured order of accuracy, and the Pareto front (docs/metrics.md, "Speed against error")."""
from __future__ import annotations

import math

import pandas as pd
import plotly.graph_objects as go

from .load import SERIES
from .style import default_labels, figure_html, fmt, trace_style


def headline_metric(rows: pd.DataFrame) -> tuple[str, str] | None:
    """The scenario's first error metric: (results.csv column, title)."""
    for _, title, _, summary in SERIES:
        if summary in rows and rows[summary].notna().any():
            return summary, title.split(" against")[0].split(" |")[0]
    return None


def convergence_order(points: pd.DataFrame, error_column: str, floors: dict[float, float] | None = None) -> float | None:
    """Least-squares slope of log(error) against log(dt): the measured order of accuracy.
    Points within 10x of the reference's own error at that dt (floors) or of round-off measure
    the reference, not the method, and are left out."""
    def above_floor(row) -> bool:
        floor = 1e-13
        for dt, self_error in (floors or {}).items():
            if abs(dt - row["dt"]) <= 1e-6 * dt and isinstance(self_error, (int, float)) and not math.isnan(self_error):
                floor = max(floor, 10 * self_error)
        return row[error_column] > floor
    valid = points[[above_floor(r) for _, r in points.iterrows()]] if not points.empty else points
    valid = valid[valid["dt"].notna()]
    if valid["dt"].nunique() < 3:
        return None
    x, y = valid["dt"].map(math.log), valid[error_column].map(math.log)
    mx, my = x.mean(), y.mean()
    denominator = ((x - mx) ** 2).sum()
    return float(((x - mx) * (y - my)).sum() / denominator) if denominator > 0 else None


def pareto_front(points: pd.DataFrame, error_column: str) -> pd.DataFrame:
    """Points no other point beats on both cost and error."""
    ordered = points.sort_values(["cost", error_column])
    keep, best = [], math.inf
    for index, row in ordered.iterrows():
        if row[error_column] < best:
            keep.append(index)
            best = row[error_column]
    return ordered.loc[keep]


def speed_error(rows: pd.DataFrame, floors: dict[float, float] | None = None) -> tuple[str | None, list[dict]]:
    """Error against cost (wall s per simulated s), one curve per engine/variant over the dt sweep
    (each engine's default variant shown, the others behind the legend), the Pareto front dashed,
    each curve's measured order in its legend; and the front as a table."""
    metric = headline_metric(rows)
    if metric is None:
        return None, []
    error_column, error_title = metric
    points = rows[(rows["status"] == "ok") & rows["steps_per_s"].notna() & rows[error_column].notna()].copy()
    if points.empty:
        return None, []
    points["cost"] = points["wall_s_median"] / points["duration"]
    swept = points["dt"].nunique() > 1
    shown = default_labels(points)
    fig = go.Figure()
    for label, curve in points.groupby("label", sort=False):
        curve = curve.sort_values("cost")
        order = convergence_order(curve, error_column, floors) if swept else None
        name = f"{label} (order {order:.2f})" if order is not None else label
        curve = curve[curve[error_column] > 0]  # a log axis has no zero
        fig.add_trace(go.Scatter(
            x=curve["cost"], y=curve[error_column], mode="lines+markers", name=name,
            visible=True if label in shown else "legendonly", **trace_style(label),
            text=[f"dt = 1/{1 / dt:.0f} s" for dt in curve["dt"]],
            hovertemplate="%{text}<br>cost %{x:.3g}<br>error %{y:.3g}"))
    front = pareto_front(points, error_column)
    drawn = front[front[error_column] > 0]
    fig.add_trace(go.Scatter(x=drawn["cost"], y=drawn[error_column], mode="lines",
                             name="Pareto front", line=dict(dash="dash", color="black", width=1)))
    fig.update_layout(title=f"Speed against error: max {error_title.lower()} against cost",
                      xaxis_title="wall s per simulated s (lower is faster)", yaxis_title="max error")
    fig.update_xaxes(type="log", exponentformat="power")
    fig.update_yaxes(type="log", exponentformat="power")
    table = [dict(label=r["label"], dt=f"1/{1 / r['dt']:.0f}", cost=fmt(r["cost"]), error=fmt(r[error_column]))
             for _, r in front.iterrows()]
    return figure_html(fig), table
