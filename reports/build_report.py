#!/usr/bin/env python3
"""Build one self-contained HTML report (index.html) from a physbench results folder.

Reads only files: results.csv, metadata.json, trajectories/*.csv, scenes/*.json and poses/*.bin,
as `physbench run` writes them. The page embeds plotly.js and the replay viewer (three.js, built
by scripts/setup.sh into reports/viewer/dist), so it opens offline.

    python reports/build_report.py results/20261122-041500
"""
from __future__ import annotations

import argparse
import html
import json
import math
import sys
from pathlib import Path

import jinja2
import pandas as pd
import plotly.graph_objects as go
import plotly.offline
from plotly.subplots import make_subplots

import compare
import replay

# the error series a trajectory CSV may hold: column, title, unit, and the results.csv summary column
SERIES = [
    ("position_err", "Position error against the reference", "m", "position_err_max"),
    ("orientation_err", "Orientation error against the reference", "rad", "orientation_err_max"),
    ("stack_drift", "Stack drift: largest horizontal displacement of any body", "m", "stack_drift_max"),
    ("penetration", "Deepest penetration (rtp's narrow phase on the true shapes)", "m", "penetration_max"),
    ("energy_drift", "Relative energy drift |E − E₀| / KE₀", "", "energy_drift_max"),
    ("linear_momentum_drift", "Linear momentum drift |P − P₀|", "kg m/s", "linear_momentum_drift_max"),
    ("angular_momentum_drift", "Relative angular momentum drift |L − L₀| / |L₀|", "", "angular_momentum_drift_max"),
]

STATUS_ORDER = ["ok", "diverged", "exploded", "unsupported", "timeout", "crashed", "error"]

# one hue an engine and one line style and marker a variant, the same on every chart of a page
ENGINE_HUES = {"rtp": "#d62728", "bullet": "#1f77b4", "ode": "#2ca02c", "box2d": "#9467bd",
               "box2d-v3": "#8c564b", "mujoco": "#ff7f0e", "mujoco-2.2": "#bcbd22", "jolt": "#17becf",
               "rapier": "#e377c2", "test-fault": "#7f7f7f"}
SPARE_HUES = ["#393b79", "#637939", "#8c6d31", "#843c39", "#7b4173"]
DASHES = ["solid", "dash", "dot", "dashdot", "longdash", "longdashdot"]
SYMBOLS = ["circle", "square", "diamond", "triangle-up", "x", "star", "cross", "pentagon", "hexagon", "triangle-down"]
_variant_index: dict[str, int] = {}


def learn_styles(results: pd.DataFrame) -> None:
    """Each engine's variants numbered in the order the results first name them, for the page."""
    _variant_index.clear()
    counts: dict[str, int] = {}
    for engine, variant in zip(results["engine"], results["variant"]):
        label = f"{engine}/{variant}"
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

# the contact table of a contact scenario: results.csv column, heading (docs/metrics.md, "Contact")
CONTACT_COLUMNS = [
    ("contact_verdict", "verdict"), ("stack_drift_max", "drift max (m)"), ("top_height_change", "top height change (m)"),
    ("penetration_max", "penetration max (m)"), ("penetration_final", "penetration final (m)"),
    ("energy_added_max", "energy added max (J)"), ("speed_max", "speed max (m/s)"),
    ("rest_speed_rms", "RMS speed, last second (m/s)"), ("apex_rel_err", "apex errors (relative)"),
    ("slide_distance", "slide (m)"), ("slide_accel", "slide a (m/s²)"), ("slide_accel_expected", "closed form a"),
    ("exchange_err", "exchange error"), ("tunnelled", "tunnelled"), ("escaped", "escaped bodies"),
]
# verdicts that answer a contact scene's question badly (reports colour them)
FAILED_VERDICTS = {"collapsed", "sinks", "drifts", "settles", "tumbled", "no bounce", "tunnelled", "stuck",
                   "exploded", "slides, should stay", "stays, should slide", "escaped", "unsettled"}

# the two views of drift against cost (docs/engines.md, "Contacts"): each engine at its own
# defaults, and each at 10 velocity iterations or the nearest it has (Bullet's and Jolt's defaults
# are 10; rtp's soft step has no iteration count, so its 10-iteration solver stands for it there)
CONTACT_VIEWS = {
    "each engine's defaults": {"rtp": "soft-step", "bullet": "float", "ode": "quickstep", "box2d": "default",
                               "mujoco": "euler", "mujoco-2.2": "euler", "box2d-v3": "default",
                               "rapier": "default", "jolt": "default"},
    "equal iterations (10)": {"rtp": "sequential-impulse", "bullet": "float", "ode": "quickstep-10",
                              "box2d": "iterations-10", "mujoco": "pgs-10", "mujoco-2.2": "pgs-10",
                              "box2d-v3": "iterations-10", "rapier": "iterations-10", "jolt": "default"},
}
# drift below this is drawn at it (a log axis has no zero)
DRIFT_FLOOR = 1e-6


def has_contact_metrics(rows: pd.DataFrame) -> bool:
    """Whether these rows come from a contact scene (they carry a penetration or drift column)."""
    return any(c in rows and rows[c].notna().any() for c in ("penetration_max", "stack_drift_max"))


def contact_table(rows: pd.DataFrame) -> list[dict]:
    """One row per engine/variant of a contact scenario: its verdict, the contact metrics it has
    and ms per step; the columns no row fills are left out."""
    if not has_contact_metrics(rows):
        return []
    present = [(c, t) for c, t in CONTACT_COLUMNS if c in rows and rows[c].notna().any()]
    table = []
    for _, r in rows.iterrows():
        ms = 1e3 / r["steps_per_s"] if pd.notna(r.get("steps_per_s")) and r["steps_per_s"] > 0 else None
        verdict = r.get("contact_verdict")
        table.append(dict(label=r["label"], status=r["status"], ms=fmt(ms),
                          failed=isinstance(verdict, str) and verdict in FAILED_VERDICTS,
                          cells=[fmt(r.get(c)) for c, _ in present]))
    return [dict(headings=[t for _, t in present], rows=table)]


def verdict_table(results: pd.DataFrame) -> dict | None:
    """Every contact scenario at its own step against every engine/variant: the verdict (stands,
    drifts, collapsed, tunnelled, …), or the status when the run did not give one."""
    contact = [name for name, rows in results.groupby("scenario", sort=False) if has_contact_metrics(rows)]
    if not contact:
        return None
    rows = []
    for label in results[results["scenario"].isin(contact)]["label"].unique():
        cells = []
        for name in contact:
            hit = results[(results["scenario"] == name) & (results["label"] == label)]
            if hit.empty:
                cells.append(("", ""))
                continue
            row = hit.iloc[0]
            verdict = row.get("contact_verdict")
            text = verdict if isinstance(verdict, str) and verdict else ("ok" if row["status"] == "ok" else row["status"])
            css = "unstable" if text in FAILED_VERDICTS or row["status"] in ("error", "crashed", "timeout") else (
                "stable" if text in ("stands", "stays", "slides", "stopped", "contained", "ok") else "")
            cells.append((text, css))
        rows.append(dict(label=label, cells=cells))
    return dict(scenarios=contact, rows=rows)


class ReportError(Exception):
    """A results folder that cannot be reported, with what is wrong and where."""


SCHEMA_FILE = Path(__file__).resolve().parents[1] / "harness" / "results-schema.json"


def check_schema(results: pd.DataFrame, csv: Path) -> None:
    """results.csv against harness/results-schema.json, the contract `physbench run` writes by: no
    column the schema lacks, every required column present and filled, numbers that parse. A column
    the schema has and the file lacks is allowed (a run from before the column joined)."""
    schema = json.loads(SCHEMA_FILE.read_text())
    columns = {c["name"]: c for c in schema["columns"]}
    unknown = [c for c in results.columns if c not in columns]
    if unknown:
        raise ReportError(f"{csv}: columns not in {SCHEMA_FILE.name}: {unknown}")
    for name, c in columns.items():
        if name not in results.columns:
            if c["required"]:
                raise ReportError(f"{csv}: missing column {name!r}, which every row must fill")
            continue
        values = results[name]
        filled = values.notna() & (values.astype(str) != "")
        if c["required"] and not filled.all():
            raise ReportError(f"{csv}: row {int((~filled).idxmax()) + 2}: {name} is empty")
        if c["type"] in ("number", "integer"):
            parsed = pd.to_numeric(values.where(filled), errors="coerce")
            wrong = filled & parsed.isna()
            if wrong.any():
                row = int(wrong.idxmax())
                raise ReportError(f"{csv}: row {row + 2}: {name} = {values[row]!r} is not a {c['type']}")
        if c["type"] == "status":
            wrong = filled & ~values.isin(schema["statuses"])
            if wrong.any():
                row = int(wrong.idxmax())
                raise ReportError(f"{csv}: row {row + 2}: status {values[row]!r} is not one of {schema['statuses']}")


def load_results(folder: Path) -> tuple[pd.DataFrame, dict]:
    csv = folder / "results.csv"
    meta = folder / "metadata.json"
    if not csv.is_file():
        raise ReportError(f"{csv}: missing (is {folder} a physbench results folder?)")
    if not meta.is_file():
        raise ReportError(f"{meta}: missing")
    try:
        results = pd.read_csv(csv, dtype={"message": str, "trajectory": str})
    except Exception as exc:  # pandas raises several types for a broken file
        raise ReportError(f"{csv}: unreadable: {exc}") from exc
    check_schema(results, csv)
    try:
        metadata = json.loads(meta.read_text())
    except json.JSONDecodeError as exc:
        raise ReportError(f"{meta}: not valid JSON: {exc}") from exc
    results["label"] = results["engine"] + "/" + results["variant"]
    return results, metadata


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


def is_nominal(meta: dict, row) -> bool:
    """Whether a row ran at its scenario's own step (a swept scenario has rows at other steps too)."""
    own = meta.get("scenarios", {}).get(row["scenario"], {}).get("dt")
    return own is None or abs(row["dt"] - own) <= 1e-6 * own


def figure_html(fig: go.Figure) -> str:
    fig.update_layout(template="plotly_white", margin=dict(l=60, r=20, t=50, b=50), height=420,
                      legend=dict(font=dict(size=11)))
    return plotly.offline.plot(fig, output_type="div", include_plotlyjs=False, config={"displaylogo": False})


def error_over_time(folder: Path, rows: pd.DataFrame, column: str, title: str, unit: str) -> str | None:
    fig = go.Figure()
    for _, row in rows.iterrows():
        if not isinstance(row.get("trajectory"), str):
            continue
        traj = pd.read_csv(folder / row["trajectory"])
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


def error_by_body(folder: Path, rows: pd.DataFrame) -> str | None:
    """Max position error of each probed body over the run, against its index: how error grows
    along a chain. Only for scenes with more than one probed body and a reference."""
    fig = go.Figure()
    for _, row in rows.iterrows():
        if not isinstance(row.get("trajectory"), str):
            continue
        traj = pd.read_csv(folder / row["trajectory"])
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
    """Error against cost (wall s per simulated s), one curve per engine/variant over the dt sweep,
    the Pareto front dashed, each curve's measured order in its legend; and the front as a table."""
    metric = headline_metric(rows)
    if metric is None:
        return None, []
    error_column, error_title = metric
    points = rows[(rows["status"] == "ok") & rows["steps_per_s"].notna() & rows[error_column].notna()].copy()
    if points.empty:
        return None, []
    points["cost"] = points["wall_s_median"] / points["duration"]
    swept = points["dt"].nunique() > 1
    fig = go.Figure()
    for label, curve in points.groupby("label", sort=False):
        curve = curve.sort_values("cost")
        order = convergence_order(curve, error_column, floors) if swept else None
        name = f"{label} (order {order:.2f})" if order is not None else label
        fig.add_trace(go.Scatter(
            x=curve["cost"], y=curve[error_column].clip(lower=1e-16), mode="lines+markers", name=name,
            **trace_style(label),
            text=[f"dt = 1/{1 / dt:.0f} s" for dt in curve["dt"]],
            hovertemplate="%{text}<br>cost %{x:.3g}<br>error %{y:.3g}"))
    front = pareto_front(points, error_column)
    fig.add_trace(go.Scatter(x=front["cost"], y=front[error_column].clip(lower=1e-16), mode="lines",
                             name="Pareto front", line=dict(dash="dash", color="black", width=1)))
    fig.update_layout(title=f"Speed against error: max {error_title.lower()} against cost",
                      xaxis_title="wall s per simulated s (lower is faster)", yaxis_title="max error")
    fig.update_xaxes(type="log", exponentformat="power")
    fig.update_yaxes(type="log", exponentformat="power")
    table = [dict(label=r["label"], dt=f"1/{1 / r['dt']:.0f}", cost=fmt(r["cost"]), error=fmt(r[error_column]))
             for _, r in front.iterrows()]
    return figure_html(fig), table


# the error a scenario's question is about, in this order of preference (results.csv column, words)
GLANCE_METRICS = [("position_err_max", "position error"), ("orientation_err_max", "orientation error"),
                  ("apex_rel_err_max", "apex error"), ("slide_accel_rel_err", "slide acceleration error"),
                  ("exchange_err", "velocity exchange error"), ("stack_drift_max", "stack drift"),
                  ("penetration_max", "deepest penetration"), ("energy_drift_max", "energy drift")]

FAILED = {"exploded": "exploded", "crashed": "crashed", "timeout": "timed out", "error": "failed",
          "diverged": "diverged"}


def at_a_glance(results: pd.DataFrame, meta: dict) -> list[dict]:
    """Per scenario, the front page's answers: which engine variant is fastest and which most accurate
    at the scene's own step, which runs are on the Pareto front of cost against error (over the step
    sweep), the best error each engine variant reaches within an equal time budget, and what failed,
    in words."""
    glance = []
    for name, rows in results.groupby("scenario", sort=False):
        nominal = rows[[is_nominal(meta, r) for _, r in rows.iterrows()]]
        ok = nominal[(nominal["status"] == "ok") & nominal["steps_per_s"].notna()]
        entry = dict(name=name, anchor=anchor_of(name), fastest="", accurate="", metric="", front="", budget="",
                     budget_rows=[], failures=[], unsupported=int((nominal["status"] == "unsupported").sum()))
        if not ok.empty:
            best = ok.loc[ok["steps_per_s"].idxmax()]
            entry["fastest"] = f"{best['label']} ({fmt(best['steps_per_s'])} steps/s)"
        metric = next(((c, t) for c, t in GLANCE_METRICS if c in rows and rows[c].notna().any()), None)
        if metric:
            column, title = metric
            entry["metric"] = title
            scored = ok[ok[column].notna()]
            if not scored.empty:
                best = scored.loc[scored[column].abs().idxmin()]
                entry["accurate"] = f"{best['label']} ({fmt(abs(best[column]))})"
            points = rows[(rows["status"] == "ok") & rows["steps_per_s"].notna() & rows[column].notna()].copy()
            if not points.empty:
                points["cost"] = points["wall_s_median"] / points["duration"]
                points[column] = points[column].abs()
                front = pareto_front(points, column)
                entry["front"] = ", ".join(f"{r['label']} at 1/{1 / r['dt']:.0f} s" for _, r in front.iterrows())
                # equal time budget: the cheapest run of the costliest engine, so that every engine
                # has a run within it; each engine's best error (any variant, any step) at that cost
                cheapest = points.groupby("engine")["cost"].min()
                budget = cheapest.max()
                within = points[points["cost"] <= budget * (1 + 1e-9)]
                best_within = within.loc[within.groupby("engine")[column].idxmin()].sort_values(column)
                entry["budget"] = fmt(budget)
                entry["budget_rows"] = [dict(label=r["label"], error=fmt(r[column]), dt=f"1/{1 / r['dt']:.0f}")
                                        for _, r in best_within.iterrows()]
        for _, r in rows.iterrows():
            if r["status"] in FAILED:
                why = r["message"] if isinstance(r.get("message"), str) and r["message"] else "no reason given"
                entry["failures"].append(f"{r['label']} {FAILED[r['status']]} at dt = {fmt(r['dt'])} s: {why}")
        glance.append(entry)
    return glance


def anchor_of(name: str) -> str:
    return "s-" + "".join(c if c.isalnum() or c in "-_" else "-" for c in name)


def families_of(meta: dict) -> dict[str, list[tuple]]:
    """Scenario families from the metadata: family -> [(parameter, scenario, info), ...]."""
    families: dict[str, list[tuple]] = {}
    for name, info in meta.get("scenarios", {}).items():
        if info.get("family"):
            families.setdefault(info["family"], []).append((info.get("parameter"), name, info))
    return families


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


def benchmark_document(folder: Path, name: str) -> dict | None:
    """A Google Benchmark JSON file bench.sh wrote into benchmarks/, or None when there is none."""
    path = folder / "benchmarks" / name
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ReportError(f"{path}: not valid JSON: {exc}") from exc


def particle_benchmark(folder: Path) -> dict | None:
    """The Google Benchmark run of the particle update, if bench.sh wrote one: the triad's bytes/s
    per thread count, and per (particles, threads) the particle-steps/s and roofline fraction."""
    document = benchmark_document(folder, "particles.json")
    if document is None:
        return None
    runs = document.get("benchmarks", [])
    triad, rows, paired = {}, [], []
    for run in runs:
        if run.get("run_type") != "iteration":
            continue
        name = run.get("name", "")
        if name.startswith("Triad/"):
            triad[int(run["threads"])] = run["bytes_per_second"]
        elif name.startswith("ThreadsPaired/"):
            paired.append(dict(particles=int(run["particles"]), speedup=run["speedup"],
                               least=run["speedup_least_block"], largest=run["speedup_largest_block"],
                               one_ms=run["one_thread_ms"], two_ms=run["two_threads_ms"],
                               rounds=int(run["rounds"]), blocks=int(run["blocks"])))
        elif name.startswith("ParticleUpdate/"):
            fields = dict(part.split(":") for part in name.split("/")[1:] if ":" in part)
            rows.append(dict(particles=int(fields["particles"]), threads=int(fields["threads"]),
                             steps=run["items_per_second"], bytes_per_step=run["bytes_per_particle_step"],
                             fraction=run.get("roofline_fraction")))
    kernels = document.get("context", {}).get("particle_kernels", "")
    return dict(triad=triad, rows=rows, at_60hz=particles_at_rate(rows, 60.0),
                kernels=kernels, paired=paired) if rows else None


def particles_at_rate(rows: list[dict], hz: float) -> list[dict]:
    """How many particles one update holds at hz steps per second, per thread count: the largest
    measured count's particle-steps/s divided by hz (throughput at large counts is flat, bound by
    memory), with whether that count lies inside the measured range or beyond it."""
    held = []
    for threads in sorted({r["threads"] for r in rows}):
        largest = max((r for r in rows if r["threads"] == threads), key=lambda r: r["particles"])
        count = largest["steps"] / hz
        held.append(dict(threads=threads, particles=count, measured_up_to=largest["particles"],
                         extrapolated=count > largest["particles"]))
    return held


def broadphase_benchmark(folder: Path) -> dict | None:
    """The broadphase benchmark (bench/broadphase_bench.cpp), if bench.sh wrote one: per case
    (motion and box count) and engine, the median µs per update with its spread over repetitions,
    pairs/s and the pair-set agreement; per engine, the time to build from scratch; and the
    chart of µs per update against the box count for coherent motion."""
    document = benchmark_document(folder, "broadphase.json")
    if document is None:
        return None
    runs = document.get("benchmarks", [])
    updates: dict[tuple, dict] = {}
    builds, paired = [], []
    for run in runs:
        parts = run.get("run_name", run.get("name", "")).split("/")
        if len(parts) < 5:
            continue
        kind, motion, count, engine = parts[0], parts[1], int(parts[2]), "/".join(parts[3:5])
        scale = {"ns": 1e-3, "us": 1.0, "ms": 1e3, "s": 1e6}[run.get("time_unit", "us")]
        if kind == "Paired" and run.get("run_type") == "iteration":
            # rtp's box pruning and this peer updated in turn, round by round (counters in µs)
            paired.append(dict(motion=motion, boxes=count, engine=engine, rounds=run.get("rounds"),
                               rtp_us=run.get("rtp_us"), peer_us=run.get("peer_us"), ratio=run.get("ratio"),
                               least=run.get("ratio_least_block"), largest=run.get("ratio_largest_block"),
                               blocks=run.get("blocks")))
        elif kind == "Build" and run.get("run_type") == "iteration":
            builds.append(dict(engine=engine, boxes=count, ms=run["real_time"] * scale / 1e3))
        elif kind == "Update":
            row = updates.setdefault((motion, count, engine), dict(motion=motion, boxes=count, engine=engine))
            aggregate = run.get("aggregate_name") if run.get("run_type") == "aggregate" else "median"
            if aggregate == "median":
                row.update(us=run["real_time"] * scale, pairs_per_s=run.get("items_per_second"),
                           exact=run.get("exact_pairs"), missing=run.get("missing_pairs"),
                           extra=run.get("extra_pairs_fraction"))
            elif aggregate == "cv":
                row["cv"] = 100.0 * run["real_time"]  # Google Benchmark writes the cv as a fraction
    if not updates:
        return None
    rows = sorted(updates.values(), key=lambda r: (r["motion"], r["boxes"], r.get("us", 0.0)))
    # each case's fastest peer, and how many times faster rtp's best variant is
    for motion, count in {(r["motion"], r["boxes"]) for r in rows}:
        case = [r for r in rows if (r["motion"], r["boxes"]) == (motion, count) and "us" in r]
        peers = [r["us"] for r in case if not r["engine"].startswith("rtp/")]
        ours = [r["us"] for r in case if r["engine"].startswith("rtp/")]
        for r in case:
            r["vs_best_peer"] = min(peers) / r["us"] if peers and r["engine"].startswith("rtp/") else None
        if peers and ours:
            for r in case:
                r["best"] = r["us"] == min(ours) or r["us"] == min(peers)
    fig = go.Figure()
    coherent = [r for r in rows if r["motion"] == "coherent" and "us" in r]
    for engine in dict.fromkeys(r["engine"] for r in coherent):
        points = sorted((r["boxes"], r["us"]) for r in coherent if r["engine"] == engine)
        fig.add_trace(go.Scatter(x=[p for p, _ in points], y=[u for _, u in points], mode="lines+markers",
                                 name=engine, line=dict(color=hue(engine)), marker=dict(color=hue(engine))))
    fig.update_layout(title="broadphase, coherent motion: time per update against box count",
                      xaxis_title="boxes", yaxis_title="µs per update, median of 5 repetitions")
    fig.update_xaxes(type="log", exponentformat="power")
    fig.update_yaxes(type="log", exponentformat="power")
    context = document.get("context", {})
    settings = {k.removeprefix("settings "): v for k, v in context.items() if k.startswith("settings ")}
    paired.sort(key=lambda r: r["ratio"] or 0.0)
    return dict(rows=rows, builds=builds, paired=paired, settings=settings,
                chart=figure_html(fig) if fig.data else "")


def narrowphase_benchmark(folder: Path) -> dict | None:
    """The narrow-phase benchmark (bench/narrowphase_bench.cpp), if bench.sh wrote one: per pair
    set (shapes/regime) and engine, the median ns per pair with its spread, how many times rtp's
    time this engine takes, and on a peer's row how rtp agrees with it on that set; the triangle
    query likewise; the settings and the comparison's tolerances."""
    document = benchmark_document(folder, "narrowphase.json")
    if document is None:
        return None
    cases: dict[tuple, dict] = {}
    paired = []
    for run in document.get("benchmarks", []):
        parts = run.get("run_name", run.get("name", "")).split("/")
        if len(parts) >= 5 and parts[0] == "Paired" and run.get("run_type") == "iteration":
            paired.append(dict(set=f"{parts[1]}/{parts[2]}", engine=f"{parts[3]}/{parts[4]}",
                               rounds=int(run["rounds"]), rtp_ns=run["rtp_ns"], peer_ns=run["peer_ns"],
                               ratio=run["ratio"], least=run["ratio_least_block"],
                               largest=run["ratio_largest_block"], blocks=int(run["blocks"])))
            continue
        if len(parts) < 5 or parts[0] not in ("Pairs", "Query"):
            continue
        key = (f"{parts[1]}/{parts[2]}", f"{parts[3]}/{parts[4]}")
        row = cases.setdefault(key, dict(set=key[0], engine=key[1]))
        aggregate = run.get("aggregate_name") if run.get("run_type") == "aggregate" else "median"
        if aggregate == "median":
            scale = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}[run.get("time_unit", "ns")]
            row["ns"] = run["real_time"] * scale / max(run.get("pairs", 1.0), 1.0)
            for counter in ("touching_fraction", "verdict_agreement", "depth_agreement", "normal_agreement",
                            "compared_contacts", "peer_refuted", "unexplained", "in_band",
                            "worst_point_difference"):
                if counter in run:
                    row[counter] = run[counter]
        elif aggregate == "cv":
            row["cv"] = 100.0 * run["real_time"]
    rows = sorted(cases.values(), key=lambda r: (r["set"], not r["engine"].startswith("rtp/"), r["engine"]))
    if not rows:
        return None
    # this engine's time over rtp's on the same set (rtp/sat, or the triangle query's rtp row)
    for r in rows:
        ours = [o["ns"] for o in rows if o["set"] == r["set"] and o["engine"] in ("rtp/sat", "rtp/voronoi")
                and "ns" in o]
        r["vs_rtp"] = r["ns"] / ours[0] if ours and "ns" in r else None
    context = document.get("context", {})
    settings = {k.removeprefix("settings "): v for k, v in context.items() if k.startswith("settings ")}
    return dict(rows=rows, settings=settings, tolerances=context.get("tolerances", ""), paired=paired)


def drift_cost_views(results: pd.DataFrame) -> list[dict]:
    """Per stack scenario (one with a drift column), max drift against ms per step in the two
    views of CONTACT_VIEWS side by side, one marker per engine, each view's Pareto front dashed;
    the fronts as a list, and the engines of a view that gave no point with their status."""
    sections = []
    for name, rows in results.groupby("scenario", sort=False):
        if "stack_drift_max" not in rows or rows["stack_drift_max"].isna().all():
            continue
        fig = make_subplots(rows=1, cols=len(CONTACT_VIEWS), subplot_titles=list(CONTACT_VIEWS),
                            shared_yaxes=True, horizontal_spacing=0.06)
        fronts, missing, seen = [], [], set()
        for col, (view, chosen) in enumerate(CONTACT_VIEWS.items(), start=1):
            picked = rows[rows.apply(lambda r: chosen.get(r["engine"]) == r["variant"], axis=1)]
            ok = picked[(picked["status"] == "ok") & picked["steps_per_s"].notna() &
                        picked["stack_drift_max"].notna()].copy()
            for _, r in picked.drop(ok.index).iterrows():
                missing.append(f"{view}: {r['label']} {r.get('contact_verdict') or r['status']}")
            if ok.empty:
                continue
            ok["cost"] = 1e3 / ok["steps_per_s"]
            ok["drift"] = ok["stack_drift_max"].clip(lower=DRIFT_FLOOR)
            for _, r in ok.iterrows():
                # a stack that failed its question otherwise (sank, settled) is an open marker
                verdict = r.get("contact_verdict") if isinstance(r.get("contact_verdict"), str) else ""
                failed = verdict in FAILED_VERDICTS
                fig.add_trace(go.Scatter(x=[r["cost"]], y=[r["drift"]], mode="markers+text", text=[r["engine"]],
                                         textposition="top center", name=r["label"], legendgroup=r["label"],
                                         showlegend=r["label"] not in seen,
                                         marker=dict(size=10, symbol="circle-open" if failed else "circle",
                                                     color=hue(r["engine"])),
                                         hovertemplate=f"{r['label']}: {verdict}<br>%{{x:.3g}} ms per step<br>"
                                                       f"drift max {fmt(r['stack_drift_max'])} m<extra></extra>"),
                              row=1, col=col)
                seen.add(r["label"])
            front = pareto_front(ok, "drift")
            fig.add_trace(go.Scatter(x=front["cost"], y=front["drift"], mode="lines", showlegend=col == 1,
                                     name="Pareto front", legendgroup="front",
                                     line=dict(dash="dash", color="black", width=1)), row=1, col=col)
            fronts.append(dict(view=view, members=[f"{r['label']} ({fmt(r['cost'])} ms, {fmt(r['stack_drift_max'])} m)"
                                                   for _, r in front.iterrows()]))
        if not fig.data:
            continue
        fig.update_layout(title=f"{name}: max drift against ms per step (drift under {DRIFT_FLOOR:g} m drawn at it)")
        fig.update_xaxes(type="log", exponentformat="power", title_text="ms per step, median")
        fig.update_yaxes(type="log", exponentformat="power")
        fig.update_yaxes(title_text="max drift (m)", row=1, col=1)
        sections.append(dict(scenario=name, chart=figure_html(fig), fronts=fronts, missing=missing))
    return sections


def contacts_benchmark(folder: Path) -> dict | None:
    """rtp's contact step on the pyramids (bench/contacts_bench.cpp), if bench.sh wrote it: per
    (base, threads) the ms per step, the bodies, contact pairs and points, the solver's ns per
    point and pass, and each stage's share of the step; the median of repetitions when there are
    any. A run without the counters is named as malformed."""
    document = benchmark_document(folder, "contacts.json")
    if document is None:
        return None
    cases: dict[tuple, dict] = {}
    for run in document.get("benchmarks", []):
        name = run.get("run_name", run.get("name", ""))
        if not name.startswith("Pyramid/"):
            continue
        aggregate = run.get("aggregate_name") if run.get("run_type") == "aggregate" else None
        if aggregate not in (None, "median"):
            continue
        fields = dict(part.split(":", 1) for part in name.split("/")[1:] if ":" in part)
        try:
            key = (int(fields["base"]), int(fields["threads"]))
            row = dict(base=key[0], threads=key[1], bodies=int(run["bodies"]), ms=float(run["ms_per_step"]),
                       pairs=int(run["contact_pairs"]), points=int(run["contact_points"]),
                       ns_point_pass=float(run["solver_ns_per_point_pass"]),
                       shares={k.removeprefix("share_"): float(v) for k, v in run.items() if k.startswith("share_")})
        except (KeyError, ValueError) as exc:
            raise ReportError(f"{folder / 'benchmarks' / 'contacts.json'}: benchmark {name!r} lacks "
                              f"or garbles {exc}") from exc
        if aggregate == "median" or key not in cases:
            cases[key] = row
    if not cases:
        return None
    rows = sorted(cases.values(), key=lambda r: (r["base"], r["threads"]))
    stages = list(dict.fromkeys(stage for r in rows for stage in r["shares"]))
    for r in rows:
        one = cases.get((r["base"], 1))
        r["speedup"] = one["ms"] / r["ms"] if one and r["threads"] != 1 and r["ms"] > 0 else None
    fig = go.Figure()
    labels = [f"base {r['base']}, {r['threads']} thread(s)" for r in rows]
    for stage in stages:
        fig.add_trace(go.Bar(x=labels, y=[r["shares"].get(stage, 0.0) for r in rows], name=stage))
    fig.update_layout(barmode="stack", title="rtp contact step: each stage's share of the step (contacts_bench)",
                      yaxis_title="share of the step")
    context = document.get("context", {})
    return dict(rows=rows, stages=stages, chart=figure_html(fig), solver=context.get("solver", ""),
                scene=context.get("scene", ""))


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


TEMPLATE = jinja2.Template("""<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<title>physbench report {{ meta.created }}</title>
<script type="text/javascript">{{ plotlyjs | safe }}</script>
<style>
 body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1200px; color: #222; padding: 0 1em; }
 table { border-collapse: collapse; margin: 0.5em 0 1.5em; font-size: 0.9em; }
 th, td { border: 1px solid #ccc; padding: 3px 7px; text-align: right; vertical-align: top; }
 th { background: #f0f0f0; } td.l, th.l { text-align: left; }
 .ok { color: #176a17; } .exploded, .diverged, .crashed, .timeout, .error { color: #b00; font-weight: bold; }
 .unsupported { color: #777; } .note { color: #555; font-size: 0.9em; }
 td.stable { background: #dff0d8; } td.unstable, td.exploded { background: #f2dede; }
 td.over-damped { background: #fcf8e3; }
 section { border-top: 2px solid #ddd; margin-top: 2em; }
 .replay-controls { display: flex; gap: 0.8em; align-items: center; flex-wrap: wrap; margin: 0.4em 0; font-size: 0.9em; }
 .replay-slider { flex: 1; min-width: 200px; } .replay-clock { font-variant-numeric: tabular-nums; }
 .replay-stage { position: relative; } .replay-canvas { display: block; cursor: grab; }
 .replay-label { position: absolute; font-size: 0.85em; font-weight: 600; background: rgba(255,255,255,0.75);
   padding: 1px 5px; pointer-events: none; } .replay-legend { color: #555; }
</style></head><body>
<h1>physbench report</h1>
<p class="note">{{ meta.created }} · commit {{ meta.git_commit or "unknown" }} · {{ meta.machine.cpu }},
 {{ meta.machine.logical_cores }} logical cores, {{ meta.machine.memory_gib }} GiB · {{ meta.machine.os }}<br>
 {{ meta.compiler }} · build {{ meta.build }}<br>command: <code>{{ meta.command }}</code><br>
 timing: {{ meta.timing.note }} (budget {{ meta.timing.budget_s }} s per job)</p>

{% if comparison %}<section id="compare"><h2>Compared with an earlier run</h2>
<p>{{ comparison.old }} → this run: {{ comparison.matched }} rows matched, speed against {{ comparison.against }}
 on {{ comparison.speed_compared }} of them ({{ comparison.method }}).
 <b>{% if comparison.regressions %}{{ comparison.regressions }} regression(s){% else %}no regression{% endif %}</b>{% if comparison.only_old %};
 {{ comparison.only_old }} rows only in the earlier run{% endif %}{% if comparison.only_new %}; {{ comparison.only_new }} only in this one{% endif %}.</p>
{% if comparison.changes %}<table><tr><th class="l">change</th><th class="l">scenario</th><th class="l">engine/variant</th><th>dt (s)</th><th class="l">what</th></tr>
{% for c in comparison.changes %}<tr><td class="l {{ c.css }}">{{ c.verdict }}</td><td class="l">{{ c.scenario }}</td><td class="l">{{ c.label }}</td>
<td>{{ c.dt }}</td><td class="l">{{ c.detail }}</td></tr>{% endfor %}</table>{% else %}<p>No change beyond the noise.</p>{% endif %}
</section>{% endif %}

{% if glance %}<section id="glance"><h2>At a glance</h2>
<p class="note">Per scenario: the fastest and the most accurate engine variant at the scene's own step;
the runs on the Pareto front of cost (wall s per simulated s) against the error the scenario asks about; the
best error each engine reaches, with any of its variants and steps, within an equal time budget (the cheapest
run of the costliest engine, so every engine has one); and every run that failed. Contents: {% for g in glance if g.linked %}<a href="#{{ g.anchor }}">{{ g.name }}</a>{% if not loop.last %} · {% endif %}{% endfor %}.</p>
<table><tr><th class="l">scenario</th><th class="l">fastest</th><th class="l">most accurate</th><th class="l">Pareto front</th>
<th class="l">equal budget: each engine's best error</th><th class="l">failures</th></tr>
{% for g in glance %}<tr><td class="l">{% if g.linked %}<a href="#{{ g.anchor }}">{{ g.name }}</a>{% else %}{{ g.name }}{% endif %}</td><td class="l">{{ g.fastest }}</td>
<td class="l">{{ g.accurate }}{% if g.metric %}<br><span class="note">{{ g.metric }}</span>{% endif %}</td><td class="l">{{ g.front }}</td>
<td class="l">{% if g.budget_rows %}<span class="note">≤ {{ g.budget }} s/s:</span> {% for b in g.budget_rows %}{{ b.label }} {{ b.error }} (dt {{ b.dt }} s){% if not loop.last %}; {% endif %}{% endfor %}{% endif %}</td>
<td class="l">{% for f in g.failures %}<span class="error">{{ f }}</span><br>{% endfor %}{% if g.unsupported %}<span class="unsupported">{{ g.unsupported }} unsupported</span>{% endif %}</td></tr>{% endfor %}
</table></section>{% endif %}

<h2>Summary</h2>
<table><tr><th class="l">scenario</th><th class="l">engine/variant</th><th class="l">status</th><th>dt (s)</th>
<th>steps/s (median)</th><th>min–max</th><th>body-steps/s</th><th>real-time ×</th>
{% for col, title in summary_columns %}<th>{{ title }}</th>{% endfor %}<th class="l">message</th></tr>
{% for r in summary_rows %}<tr><td class="l">{{ r.scenario }}</td><td class="l">{{ r.label }}</td>
<td class="l {{ r.status }}">{{ r.status }}{% if r.reference_failed %}<br><span class="error">reference {{ r.reference_failed }}</span>{% endif %}</td><td>{{ r.dt }}</td><td>{{ r.sps }}</td><td>{{ r.spread }}</td>
<td>{{ r.bsps }}</td><td>{{ r.rtf }}</td>{% for v in r.errors %}<td>{{ v }}</td>{% endfor %}
<td class="l">{{ r.message }}</td></tr>{% endfor %}</table>

{% for s in scenarios %}<section id="{{ s.anchor }}"><h2>{{ s.name }}</h2>
<p>{{ s.description }}<br><em>{{ s.question }}</em></p>
<p class="note">dt {{ s.dt }} s · {{ s.duration }} s simulated · reference: {{ s.reference }}
{% if s.self_error %} · reference changes by at most {{ s.self_error }} when its step is halved (its own error){% endif %}
{% for f in s.reference_failures %}<br><span class="error">the reference at dt {{ f.dt }} s did not run, so rows at that step have no position or orientation error: {{ f.why }}</span>{% endfor %}
{% if s.sweep %}<br>speed against error swept over dt = {{ s.sweep }} s; the charts above the sweep use dt {{ s.dt }} s{% endif %}
 · scene files in <code>scenes/</code></p>
{% for t in s.contact %}<table><tr><th class="l">engine/variant</th><th class="l">status</th><th>ms per step</th>
{% for h in t.headings %}<th>{{ h }}</th>{% endfor %}</tr>
{% for r in t.rows %}<tr><td class="l">{{ r.label }}</td><td class="l {{ r.status }}">{{ r.status }}</td><td>{{ r.ms }}</td>
{% for v in r.cells %}<td class="{{ 'unstable' if r.failed and loop.first else '' }}">{{ v }}</td>{% endfor %}</tr>{% endfor %}
</table>{% endfor %}
{% if s.replay %}<h3>Replay</h3>
<p class="note">Each engine's recorded run (its default variant) side by side, on one clock and one camera (drag to
orbit, scroll to zoom); colours by speed, body or engine, and on contact scenes by each body's deepest penetration,
with the contact points on demand (both from rtp's narrow phase on each engine's poses; docs/viewer.md). {{ s.replay.note }}.</p>
{% if s.replay.json %}<div class="replay" data-replay="replay-{{ loop.index }}"></div>
<script type="application/json" id="replay-{{ loop.index }}">{{ s.replay.json | safe }}</script>
{% if not viewerjs %}<p class="error">The replay viewer is not built: scripts/setup.sh builds it (npm ci, then npm run build in reports/viewer).</p>{% endif %}{% endif %}{% endif %}
{% for chart in s.charts %}{{ chart | safe }}{% endfor %}
{% if s.front %}<table><tr><th class="l" colspan="4">Pareto front: nothing else is both faster and more accurate</th></tr>
<tr><th class="l">engine/variant</th><th>dt (s)</th><th>wall s per simulated s</th><th>max error</th></tr>
{% for p in s.front %}<tr><td class="l">{{ p.label }}</td><td>{{ p.dt }}</td><td>{{ p.cost }}</td><td>{{ p.error }}</td></tr>{% endfor %}
</table>{% endif %}
{% if s.unsupported %}<p class="note">Not run: {% for u in s.unsupported %}<br>{{ u }}{% endfor %}</p>{% endif %}
</section>{% endfor %}

{% if verdicts %}<section><h2>Contact verdicts</h2>
<p class="note">Each contact scenario's verdict per engine and variant (docs/metrics.md, "Contact"): stands (drift and
top-height change within 1 cm), settles (the top sank over 1 cm), drifts (over 1 cm sideways), sinks (final
penetration over 2 cm), collapsed (over 0.5 m), tumbled / no bounce (a dropped box), stays / slides (a slope),
tunnelled / stuck / stopped (a fast box at a wall), contained / escaped / unsettled (boxes rained into a
container: all inside and at rest, some outside, still moving over 0.05 m/s RMS in the last second); otherwise
the run's status.</p>
<table><tr><th class="l">engine/variant</th>{% for n in verdicts.scenarios %}<th>{{ n }}</th>{% endfor %}</tr>
{% for r in verdicts.rows %}<tr><td class="l">{{ r.label }}</td>{% for text, css in r.cells %}<td class="{{ css }}">{{ text }}</td>{% endfor %}</tr>{% endfor %}
</table></section>{% endif %}

{% if drift_cost %}<section><h2>Stacks: drift against cost</h2>
<p><em>Which engine keeps a stack standing for the least time per step? Max drift (the largest horizontal
displacement of any box) against ms per step, each scenario in two views: every engine at its own defaults, and
every engine at 10 velocity iterations or its nearest (docs/engines.md, "Contacts"). The dashed line is the
Pareto front: nothing else in that view is both faster and drifts less. An open marker is a stack whose verdict
is a failure (it drifted, settled, sank or collapsed): drift is one of its criteria, not all.</em></p>
<p class="note">Variants: {% for view, chosen in contact_views.items() %}{{ view }}: {% for e, v in chosen.items() %}{{ e }}/{{ v }}{{ ", " if not loop.last }}{% endfor %}{{ "; " if not loop.last else "." }}{% endfor %}
An engine that exploded, failed or did not run has no point; its status is listed under the chart.</p>
{% for d in drift_cost %}<h3>{{ d.scenario }}</h3>{{ d.chart | safe }}
<p class="note">{% for f in d.fronts %}Pareto front, {{ f.view }}: {{ f.members | join("; ") }}<br>{% endfor %}
{% if d.missing %}No point: {{ d.missing | join("; ") }}{% endif %}</p>{% endfor %}
</section>{% endif %}

{% if contacts %}<section><h2>rtp contact step on the pyramids (contacts_bench)</h2>
<p><em>What does rtp's contact step cost per pyramid base and thread count, and where does the time go?
Google Benchmark, same session (bench/contacts_bench.cpp); {{ contacts.solver }}; {{ contacts.scene }}.
The ms per step are also drawn as crosses on the pyramid scaling chart.</em></p>
{{ contacts.chart | safe }}
<table><tr><th>base</th><th>threads</th><th>bodies</th><th>contact pairs</th><th>contact points</th><th>ms per step</th>
<th>speedup over 1 thread</th><th>solver ns per point and pass</th>{% for st in contacts.stages %}<th>{{ st.replace("_", " ") }}</th>{% endfor %}</tr>
{% for r in contacts.rows %}<tr><td>{{ r.base }}</td><td>{{ r.threads }}</td><td>{{ r.bodies }}</td><td>{{ r.pairs }}</td>
<td>{{ r.points }}</td><td>{{ "%.3g" % r.ms }}</td><td>{{ "%.2f×" % r.speedup if r.speedup }}</td><td>{{ "%.3g" % r.ns_point_pass }}</td>
{% for st in contacts.stages %}<td>{{ "%.1f %%" % (100 * r.shares.get(st, 0)) }}</td>{% endfor %}</tr>{% endfor %}
</table></section>{% endif %}

{% for f in families %}<section><h2>Stability map: {{ f.name }}</h2>
<p>{{ f.description }}</p>
<p class="note">stable: energy bounded; unstable: it grows (or exceeds 20× its start); over-damped: an undamped
system lost over half its energy; exploded: the state became non-finite or ran away.</p>
<table><tr><th class="l">{{ f.parameter_name }} →</th>{% for p, n in f.groups %}<th colspan="{{ n }}">{{ p }}</th>{% endfor %}</tr>
<tr><th class="l">engine/variant \\ dt (s)</th>{% for c in f.columns %}<th>{{ c[3] }}</th>{% endfor %}</tr>
{% for r in f.rows %}<tr><td class="l">{{ r.label }}</td>{% for text, css in r.cells %}<td class="{{ css }}">{{ text }}</td>{% endfor %}</tr>{% endfor %}
</table></section>{% endfor %}

{% for f in scaling %}<section><h2>Scaling: {{ f.name }}</h2>
<p><em>{{ f.question }}</em></p>
{{ f.chart | safe }}
{% if f.skipped %}<p class="note">Not run: {% for u in f.skipped %}<br>{{ u }}{% endfor %}</p>{% endif %}
{% if benchmark and f.name == "particles-scaling" %}
<table><tr><th class="l" colspan="5">rtp particle update (midpoint, attractor mode{{ ", " ~ benchmark.kernels ~ " kernels" if benchmark.kernels else "" }}), Google Benchmark, same session</th></tr>
<tr><th>particles</th><th>threads</th><th>particle-steps/s</th><th>bytes per particle-step</th><th>fraction of the triad roofline</th></tr>
{% for r in benchmark.rows %}<tr><td>{{ r.particles }}</td><td>{{ r.threads }}</td><td>{{ "%.3g" % r.steps }}</td>
<td>{{ r.bytes_per_step }}</td><td>{{ "%.2f" % r.fraction if r.fraction is not none else "" }}</td></tr>{% endfor %}
</table>
<p>At 60 Hz (16.7 ms per step) rtp's update holds {% for h in benchmark.at_60hz %}{{ "%.2g" % h.particles }} particles
on {{ h.threads }} thread(s){{ " (extrapolated from " ~ h.measured_up_to ~ ", the largest count measured)" if h.extrapolated else "" }}{{ "; " if not loop.last else "." }}{% endfor %}
The seed ran 200,000 at 60 FPS.</p>
{% if benchmark.paired %}<table><tr><th class="l" colspan="5">two threads against one, stepped in turn (each round a step of
each, so both meet the machine in the same state)</th></tr>
<tr><th>particles</th><th>rounds</th><th>1 thread (ms/step)</th><th>2 threads (ms/step)</th><th>speedup (least–largest block)</th><th>blocks</th></tr>
{% for r in benchmark.paired %}<tr><td>{{ r.particles }}</td><td>{{ r.rounds }}</td><td>{{ "%.2f" % r.one_ms }}</td><td>{{ "%.2f" % r.two_ms }}</td>
<td>{{ "%.2f" % r.speedup }}× ({{ "%.2f" % r.least }}–{{ "%.2f" % r.largest }})</td><td>{{ r.blocks }}</td></tr>{% endfor %}
</table>{% endif %}{% endif %}
</section>{% endfor %}

{% if narrowphase %}<section><h2>Narrow phase</h2>
<p><em>Do two shapes touch, along which normal, how deep? rtp's separating axis test with clipping against
Bullet's box-box detector and GJK/EPA, on the same random pose pairs, in the same run
(bench/narrowphase_bench.cpp). On a peer's row, how rtp agrees with that peer on the set: the verdict outside
the tolerance band, depth and normal where both report a contact; "peer refuted" counts disagreements that
exact geometry settles for rtp, "unexplained" the rest. Tolerances: {{ narrowphase.tolerances }}.</em></p>
<table><tr><th class="l">pairs</th><th class="l">engine</th><th>ns per pair (median)</th><th>cv %</th>
<th>time ÷ rtp's</th><th>touching</th><th>verdict agrees</th><th>depth agrees</th><th>normal agrees</th>
<th>peer refuted</th><th>unexplained</th></tr>
{% for r in narrowphase.rows %}<tr><td class="l">{{ r.set }}</td><td class="l">{{ r.engine }}</td>
<td>{{ "%.4g" % r.ns if r.ns is defined }}</td><td>{{ "%.2g" % r.cv if r.cv is defined }}</td>
<td>{{ "%.2f×" % r.vs_rtp if r.vs_rtp }}</td><td>{{ "%.2f" % r.touching_fraction if r.touching_fraction is defined }}</td>
<td>{{ "%.4f" % r.verdict_agreement if r.verdict_agreement is defined }}</td>
<td>{{ "%.4f" % r.depth_agreement if r.depth_agreement is defined }}</td>
<td>{{ "%.4f" % r.normal_agreement if r.normal_agreement is defined }}</td>
<td>{{ "%.0f" % r.peer_refuted if r.peer_refuted is defined }}</td>
<td>{{ "%.0f" % r.unexplained if r.unexplained is defined }}</td></tr>{% endfor %}
</table>
{% if narrowphase.paired %}<table><tr><th class="l" colspan="6">rtp/sat and a peer on the same set in turn (each round
every pair by rtp, then by the peer, so both meet the machine in the same state)</th></tr>
<tr><th class="l">pairs</th><th class="l">peer</th><th>rounds</th><th>rtp ns per pair</th><th>peer ns per pair</th>
<th>peer ÷ rtp (least–largest block)</th><th>blocks</th></tr>
{% for r in narrowphase.paired %}<tr><td class="l">{{ r.set }}</td><td class="l">{{ r.engine }}</td><td>{{ r.rounds }}</td>
<td>{{ "%.1f" % r.rtp_ns }}</td><td>{{ "%.1f" % r.peer_ns }}</td>
<td>{{ "%.2f" % r.ratio }}× ({{ "%.2f" % r.least }}–{{ "%.2f" % r.largest }})</td><td>{{ r.blocks }}</td></tr>{% endfor %}
</table>{% endif %}
<table><tr><th class="l">narrow phase</th><th class="l">version and settings (setting: value (why))</th></tr>
{% for name, text in narrowphase.settings.items() %}<tr><td class="l">{{ name }}</td><td class="l">{{ text }}</td></tr>{% endfor %}
</table>
</section>{% endif %}

{% if broadphase %}<section><h2>Broad phase</h2>
<p><em>Which pairs of N moving unit boxes overlap, and how fast does each engine's broad phase say so? Only the
broad phase runs in every engine; each pair set is compared with the exact one on the frames before timing
(a missing pair is a failure; extra pairs come from fattened bounds). bench/broadphase_bench.cpp, same session.</em></p>
{{ broadphase.chart | safe }}
<table><tr><th class="l">motion</th><th>boxes</th><th class="l">engine</th><th>µs per update (median)</th><th>cv %</th>
<th>pairs/s</th><th>exact pairs</th><th>missing</th><th>extra (fraction of exact)</th><th>best peer ÷ this</th></tr>
{% for r in broadphase.rows %}<tr><td class="l">{{ r.motion }}</td><td>{{ r.boxes }}</td><td class="l">{{ "<b>"|safe if r.best }}{{ r.engine }}{{ "</b>"|safe if r.best }}</td>
<td>{{ "%.4g" % r.us if r.us is defined }}</td><td>{{ "%.2g" % r.cv if r.cv is defined }}</td><td>{{ "%.3g" % r.pairs_per_s if r.pairs_per_s }}</td>
<td>{{ "%.0f" % r.exact if r.exact is not none }}</td><td>{{ "%.0f" % r.missing if r.missing is not none }}</td>
<td>{{ "%.3f" % r.extra if r.extra is not none }}</td><td>{{ "%.1f×" % r.vs_best_peer if r.vs_best_peer }}</td></tr>{% endfor %}
</table>
{% if broadphase.paired %}<p class="note">Paired: rtp/box-pruning and one peer updated in turn on the same
case, one update each per round, so both meet the same state of the machine; the ratio is of the times summed
over all rounds, its spread the least and largest ratio over consecutive blocks of rounds
({{ broadphase.paired[0].blocks or "?" }} blocks).</p>
<table><tr><th class="l">motion</th><th>boxes</th><th class="l">peer</th><th>rounds</th><th>peer µs per update</th>
<th>rtp/box-pruning µs</th><th>peer ÷ rtp</th><th>least–largest block</th></tr>
{% for r in broadphase.paired %}<tr><td class="l">{{ r.motion }}</td><td>{{ r.boxes }}</td><td class="l">{{ r.engine }}</td>
<td>{{ "%.0f" % r.rounds if r.rounds }}</td><td>{{ "%.4g" % r.peer_us if r.peer_us }}</td><td>{{ "%.4g" % r.rtp_us if r.rtp_us }}</td>
<td>{{ "%.2f×" % r.ratio if r.ratio }}</td><td>{{ "%.2f–%.2f" % (r.least, r.largest) if r.least and r.largest }}</td></tr>{% endfor %}
</table>{% endif %}
{% if broadphase.builds %}<table><tr><th class="l">build from scratch</th><th>boxes</th><th>ms</th></tr>
{% for b in broadphase.builds %}<tr><td class="l">{{ b.engine }}</td><td>{{ b.boxes }}</td><td>{{ "%.3g" % b.ms }}</td></tr>{% endfor %}
</table>{% endif %}
<table><tr><th class="l">broad phase</th><th class="l">version and settings (setting=value (why))</th></tr>
{% for name, text in broadphase.settings.items() %}<tr><td class="l">{{ name }}</td><td class="l">{{ text }}</td></tr>{% endfor %}
</table>
</section>{% endif %}

<section><h2>Engine settings</h2>
<p class="note">Every setting an adapter changes from its engine's defaults, as the adapter states it.</p>
{% for e in engines %}<h3>{{ e.name }} <small>{{ e.version }}</small></h3>
{% for v in e.variants %}<table><tr><th class="l" colspan="3">variant {{ v.name }}</th></tr>
<tr><th class="l">setting</th><th class="l">value</th><th class="l">why</th></tr>
{% for s in v.settings %}<tr><td class="l">{{ s.name }}</td><td class="l">{{ s.value }}</td><td class="l">{{ s.why }}</td></tr>{% endfor %}
</table>{% endfor %}{% endfor %}</section>
{% if viewerjs and has_replays %}<script>{{ viewerjs | safe }}</script>{% endif %}
</body></html>
""", autoescape=True)


def reference_failed(row) -> str:
    """The status of the converged reference a row needed when that reference did not run
    ("timeout", "error", …), else "": such a row has no position or orientation error."""
    status = row.get("reference_status")
    return status if isinstance(status, str) and status and status != "ok" else ""


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


def build_report(folder: Path, compare_with: Path | None = None) -> Path:
    results, meta = load_results(folder)
    learn_styles(results)
    comparison = comparison_section(compare_with, folder)
    present = [(c, t) for c, t, _, summary in SERIES if summary in results and results[summary].notna().any()]
    summary_columns = [(c, f"{c.replace('_', ' ')} max") for c, _ in present]

    # the summary holds each scenario at its own step; families appear as their stability maps
    # a contact family (pyramids) also has its sections: its drift and penetration are the question
    in_family = {n for n, i in meta.get("scenarios", {}).items()
                 if i.get("family") and not has_contact_metrics(results[results["scenario"] == n])}
    nominal = results[[is_nominal(meta, r) and r["scenario"] not in in_family for _, r in results.iterrows()]]
    summary_rows = []
    for _, r in nominal.iterrows():
        spread = ""
        if pd.notna(r["steps_per_s"]):
            spread = f"{fmt(r['steps_per_s_min'])}–{fmt(r['steps_per_s_max'])}"
        summary_rows.append(dict(
            scenario=r["scenario"], label=r["label"], status=r["status"], dt=fmt(r.get("dt")),
            sps=fmt(r["steps_per_s"]), spread=spread, bsps=fmt(r.get("body_steps_per_s")),
            rtf=fmt(r.get("realtime_factor")),
            errors=[fmt(r.get(f"{c}_max")) for c, _ in present],
            reference_failed=reference_failed(r),
            message=r["message"] if isinstance(r.get("message"), str) else ""))

    replays = replay.replays(folder, results, meta)
    scenarios = []
    for name, rows in results.groupby("scenario", sort=False):
        info = meta.get("scenarios", {}).get(name, {})
        if name in in_family:
            continue  # shown as its family's stability map or scaling chart
        own = rows[[is_nominal(meta, r) for _, r in rows.iterrows()]]
        charts = []
        for column, title, unit, summary in SERIES:
            if summary in own and own[summary].notna().any():
                chart = error_over_time(folder, own, column, title, unit)
                if chart:
                    charts.append(chart)
        chart = error_by_body(folder, own)
        if chart:
            charts.append(chart)
        chart = throughput_chart(own)
        if chart:
            charts.append(chart)
        self_errors = info.get("reference_self_error")
        floors = {float(k): v for k, v in self_errors.items()} if isinstance(self_errors, dict) else None
        chart, front = speed_error(rows, floors)
        if chart:
            charts.append(chart)
        self_errors = info.get("reference_self_error")
        if isinstance(self_errors, dict):
            values = [v for v in self_errors.values() if isinstance(v, (int, float))]
            self_error = max(values) if values else None
        else:
            self_error = self_errors if isinstance(self_errors, (int, float)) else None
        sweep = sorted(info.get("sweep_dt", []))
        scenarios.append(dict(
            name=name, anchor=anchor_of(name), description=info.get("description", ""), question=info.get("question", ""),
            dt=fmt(info.get("dt")), duration=fmt(info.get("duration")), reference=info.get("reference", ""),
            self_error=fmt(self_error) if self_error is not None else "",
            reference_failures=[dict(dt=fmt(float(dt)), why=why)
                                for dt, why in (info.get("reference_failure") or {}).items()],
            sweep=", ".join(f"1/{1 / dt:.0f}" for dt in sweep) if len(sweep) > 1 else "",
            charts=charts, front=front, contact=contact_table(own), replay=replays.get(name),
            unsupported=[f"{r['label']}: {r['message']}" for _, r in own.iterrows() if r["status"] == "unsupported"]))

    glance = at_a_glance(results, meta)
    shown = {s["name"] for s in scenarios}
    for g in glance:
        g["linked"] = g["name"] in shown  # a family member is drawn in its family's map or chart
    families = stability_maps(results, meta)
    benchmark = particle_benchmark(folder)
    contacts = contacts_benchmark(folder)
    scaling = scaling_charts(results, meta, benchmark, contacts)
    nominal_all = results[[is_nominal(meta, r) for _, r in results.iterrows()]]

    engines = []
    for name, info in meta.get("engines", {}).items():
        info = info or {}  # older runs wrote null for an engine that only had unsupported rows
        variants = [dict(name=v, settings=s) for v, s in info.get("variants", {}).items()]
        engines.append(dict(name=name, version=info.get("version", ""), variants=variants))

    page = TEMPLATE.render(meta=meta, plotlyjs=plotly.offline.get_plotlyjs(), summary_columns=summary_columns,
                           summary_rows=summary_rows, scenarios=scenarios, families=families, scaling=scaling,
                           benchmark=benchmark, broadphase=broadphase_benchmark(folder),
                           verdicts=verdict_table(nominal_all), drift_cost=drift_cost_views(nominal_all),
                           contact_views=CONTACT_VIEWS, contacts=contacts,
                           narrowphase=narrowphase_benchmark(folder), engines=engines,
                           viewerjs=replay.viewer_script(), has_replays=any(r["json"] for r in replays.values()),
                           comparison=comparison, glance=glance)
    out = folder / "index.html"
    partial = folder / "index.html.partial"
    partial.write_text(page, encoding="utf-8")
    partial.replace(out)  # never a half-written report
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path, help="a results folder written by `physbench run`")
    parser.add_argument("--compare", type=Path, metavar="OLD",
                        help="an earlier results folder: the page opens with what changed since (physbench compare)")
    args = parser.parse_args(argv)
    try:
        out = build_report(args.results, args.compare)
    except ReportError as exc:
        print(f"build_report: {exc}", file=sys.stderr)
        return 2
    print(f"report: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
