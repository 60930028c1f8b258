"""Scaling charts: the families that vary a count, as throughput against the count (particles,
with the memory roofline from particles_bench) or ms per step against bodies (the pyramids, with
contacts_bench's figures), log-log."""
from __future__ import annotations

import pandas as pd
import plotly.graph_objects as go

from .contacts import has_contact_metrics
from .load import families_of
from .stability import has_stability
from .style import figure_html, trace_style


def scaling_charts(results: pd.DataFrame, meta: dict, benchmark: dict | None = None,
                   contacts: dict | None = None) -> list[dict]:
    """For families that vary a count (particles-scaling): body- or particle-steps/s against the
    count on log-log axes, one curve per engine/variant, with the memory-bandwidth roofline when
    the metadata carries one."""
    families = families_of(meta)
    charts = []
    for family, members in families.items():
        names = [m[1] for m in members]
        rows = results[results["scenario"].isin(names)]
        if has_stability(rows):
            continue  # a stability map
        parameter = {name: value for value, name, _ in members}
        fig = go.Figure()
        if has_contact_metrics(rows):
            # a body-count series of a contact scene: ms per step against the bodies, log-log
            for label, curve in rows[rows["steps_per_s"].notna()].groupby("label", sort=False):
                curve = curve.sort_values("bodies")
                fig.add_trace(go.Scatter(x=curve["bodies"], y=1e3 / curve["steps_per_s"], mode="lines+markers",
                                         name=label, **trace_style(label)))
            if not fig.data:
                continue
            if contacts and family == "pyramid":
                for threads in sorted({r["threads"] for r in contacts["rows"]}):
                    points = sorted((r["bodies"], r["ms"]) for r in contacts["rows"] if r["threads"] == threads)
                    fig.add_trace(go.Scatter(x=[b for b, _ in points], y=[m for _, m in points], mode="markers",
                                             marker=dict(symbol="x", size=10),
                                             name=f"rtp soft-step, contacts_bench, {threads} thread(s)"))
            fig.update_layout(title=f"{family}: ms per step against bodies", xaxis_title="dynamic bodies",
                              yaxis_title="ms per step, median")
            fig.update_xaxes(type="log", exponentformat="power")
            fig.update_yaxes(type="log", exponentformat="power")
            skipped = [f"{r['label']} at {parameter[r['scenario']]:g}: {r['message']}"
                       for _, r in rows.iterrows() if r["status"] == "unsupported"]
            charts.append(dict(name=family, chart=figure_html(fig), question=members[0][2].get("question", ""),
                               skipped=skipped))
            continue
        for label, curve in rows[rows["body_steps_per_s"].notna()].groupby("label", sort=False):
            counts = curve["scenario"].map(parameter)
            order = counts.argsort()
            fig.add_trace(go.Scatter(x=counts.iloc[order], y=curve["body_steps_per_s"].iloc[order],
                                     mode="lines+markers", name=label, **trace_style(label)))
        if not fig.data:
            continue
        if benchmark and family == "particles-scaling":
            counts = sorted(parameter.values())
            for threads, bandwidth in sorted(benchmark["triad"].items()):
                roof = bandwidth / benchmark["rows"][0]["bytes_per_step"]
                fig.add_trace(go.Scatter(x=[counts[0], counts[-1]], y=[roof, roof], mode="lines",
                                         name=f"roofline, {threads} thread(s): triad / bytes per particle-step",
                                         line=dict(dash="dot", color="black" if threads == 1 else "grey")))
            for threads in sorted({r["threads"] for r in benchmark["rows"]}):
                points = sorted((r["particles"], r["steps"]) for r in benchmark["rows"] if r["threads"] == threads)
                fig.add_trace(go.Scatter(x=[p for p, _ in points], y=[v for _, v in points], mode="markers",
                                         marker=dict(symbol="x", size=10),
                                         name=f"rtp midpoint, Google Benchmark, {threads} thread(s)"))
        parameter_name = members[0][2].get("parameter_name", "count")
        fig.update_layout(title=f"{family}: throughput against {parameter_name}", xaxis_title=parameter_name,
                          yaxis_title="particle- (or body-) steps/s, median")
        fig.update_xaxes(type="log", exponentformat="power")
        fig.update_yaxes(type="log", exponentformat="power")
        skipped = [f"{r['label']} at {parameter[r['scenario']]:g}: {r['message']}"
                   for _, r in rows.iterrows() if r["status"] == "unsupported"]
        charts.append(dict(name=family, chart=figure_html(fig), question=members[0][2].get("question", ""),
                           skipped=skipped))
    return charts
