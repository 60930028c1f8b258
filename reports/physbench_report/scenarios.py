"""One section per scenario: its contact table, replay, error over time for every engine on one
chart (drift, penetration and energy in joules on contact scenes), error per body along a chain,
throughput, and speed against error with its Pareto front; each chart under its question, each
engine's default variant shown and its others behind the legend."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import plotly.graph_objects as go

from .contacts import contact_table, has_contact_metrics
from .load import SERIES, is_nominal, trajectories
from .speed import speed_error
from .style import anchor_of, default_labels, figure_html, fmt, hue, trace_style


# the question above each chart over time, by the trajectory column it draws
QUESTIONS = {
    "position_err": "How far from the reference does each engine put the bodies, as time goes on?",
    "orientation_err": "How far does each engine turn the bodies from the reference, as time goes on?",
    "stack_drift": "How far sideways does each engine let the stack drift, as time goes on?",
    "penetration": "How deep do each engine's bodies sink into each other, as time goes on?",
    "energy_drift": "How far does each engine let the energy stray from its start, against the energy in play?",
    "energy_joules": "How many joules does each engine add to the scene or take from it, as time goes on?",
    "linear_momentum_drift": "Does each engine keep the linear momentum, as time goes on?",
    "angular_momentum_drift": "Does each engine keep the angular momentum, as time goes on?",
}


def mechanical_energy(traj: pd.DataFrame, scene: dict) -> pd.Series:
    """E(t) in J of the probed bodies, by sample time, as the harness computes it for energy drift
    (validation/src/metrics.cpp, invariants_of): kinetic, linear and about the centre of mass with
    the world inertia R I Rᵀ, plus gravitational −m g·x, plus the springs whose moving ends are probed."""
    bodies = scene.get("bodies", [])
    gravity = np.asarray(scene.get("gravity", [0.0, 0.0, 0.0]), float)
    index = traj["body"].to_numpy(int)
    known = index < len(bodies)  # particles (past the bodies) are not on a contact scene's chart
    traj, index = traj[known], index[known]
    # per scene body, then per row: a pyramid's trajectory has millions of rows
    masses = np.array([float(b["mass"]) for b in bodies])
    moments = np.array([principal_inertia(b.get("shape", {}), m) for b, m in zip(bodies, masses)]).reshape(-1, 3)
    mass, inertia = masses[index], moments[index]
    speed2 = sum(traj[c].to_numpy(float) ** 2 for c in ("vx", "vy", "vz"))
    height = sum(-g * traj[c].to_numpy(float) for g, c in zip(gravity, ("px", "py", "pz")))
    energy = 0.5 * mass * speed2 + spin_energy(traj, inertia) + mass * height
    energy = np.where(mass > 0, energy, 0.0)
    total = pd.Series(energy, index=traj.index).groupby(traj["time"].to_numpy()).sum()
    for spring in scene.get("springs", []):
        stored = spring_energy(traj, spring)
        if stored is not None:
            total = total.add(stored, fill_value=0.0)
    return total


def principal_inertia(shape: dict, mass: float) -> list[float]:
    """A shape's principal moments (kg m²), as the adapters' scene.cpp gives them."""
    if shape.get("type") == "box":
        a, b, c = (float(h) ** 2 for h in shape.get("half_extents", [0.5, 0.5, 0.5]))
        return [mass / 3.0 * (b + c), mass / 3.0 * (a + c), mass / 3.0 * (a + b)]
    if shape.get("type") == "sphere":
        return [0.4 * mass * float(shape.get("radius", 0.5)) ** 2] * 3
    return [0.0, 0.0, 0.0]


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Each vector v rotated by its unit quaternion q (w, x, y, z), row by row."""
    u, w = q[:, 1:], q[:, :1]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def spin_energy(traj: pd.DataFrame, inertia: np.ndarray) -> np.ndarray:
    """½ ωᵀ R I Rᵀ ω of each row: ½ Σ I_k (a_k · ω)², a_k the body's k-th axis in the world, a
    column of R, from the quaternion column by column (a pyramid's millions of rows)."""
    w, x, y, z = (traj[c].to_numpy(float) for c in ("qw", "qx", "qy", "qz"))
    norm = np.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    ox, oy, oz = (traj[c].to_numpy(float) for c in ("wx", "wy", "wz"))
    axes = [(1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)),
            (2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)),
            (2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y))]
    return 0.5 * sum(inertia[:, k] * (a[0] * ox + a[1] * oy + a[2] * oz) ** 2 for k, a in enumerate(axes))


def spring_energy(traj: pd.DataFrame, spring: dict) -> pd.Series | None:
    """½ k (|pa − pb| − rest)² by sample time, or None when an end's body is not probed."""
    def end(body: int, local) -> tuple[np.ndarray, np.ndarray] | None:
        """The spring's end on this body, in the world, and the sample times; None if not probed."""
        mine = traj[traj["body"] == body].sort_values("time")
        if mine.empty:
            return None
        q = mine[["qw", "qx", "qy", "qz"]].to_numpy(float)
        q = q / np.linalg.norm(q, axis=1, keepdims=True)
        point = np.broadcast_to(np.asarray(local, float), (len(mine), 3))
        return mine[["px", "py", "pz"]].to_numpy(float) + rotate(q, point), mine["time"].to_numpy()
    a = end(int(spring.get("body_a", 0)), spring.get("local_point_a", [0, 0, 0]))
    if a is None:
        return None
    pa, times = a
    if int(spring.get("body_b", -1)) >= 0:
        b = end(int(spring["body_b"]), spring.get("point_b", [0, 0, 0]))
        if b is None:
            return None
        pb = b[0]
    else:
        pb = np.asarray(spring.get("point_b", [0, 0, 0]), float)
    stretch = np.linalg.norm(pa - pb, axis=1) - float(spring.get("rest_length", 0.0))
    return pd.Series(0.5 * float(spring.get("stiffness", 0.0)) * stretch ** 2, index=times)


def per_time(traj: pd.DataFrame, column: str, scene: dict | None) -> pd.Series | None:
    """A chart's series by sample time: the worst probed body's value of an error column, or, for
    energy on a contact scene (scene given), E − E₀ in J of every probed body (the harness's
    energy_change_j column; from the kept states in a folder written before it)."""
    if column == "energy_drift" and scene is not None:
        # the harness's E(t) − E(0) of every probed body; a folder from before it, from the states
        if "energy_change_j" in traj and traj["energy_change_j"].notna().any():
            return traj.groupby("time", sort=True)["energy_change_j"].first()
        if not {"qw", "vx", "wx", "px"} <= set(traj.columns):
            return None
        energy = mechanical_energy(traj, scene).sort_index()
        return energy - energy.iloc[0] if len(energy) else None
    if column not in traj or traj[column].isna().all():
        return None
    return traj.groupby("time", sort=True)[column].max()


def error_over_time(rows: pd.DataFrame, series: dict, column: str, title: str, unit: str,
                    scene: dict | None = None) -> dict | None:
    """One error column of the trajectories (series: load.trajectories of these rows) over time, on
    a log axis from the first sample after the start: the worst probed body at each sample, one
    line per engine shown (its default variant), its other variants behind the legend. With the
    scene of a contact scenario, energy is drawn as the joules gained or lost, |E − E₀|."""
    joules = column == "energy_drift" and scene is not None
    lines = {}
    for index in rows.index:
        values = per_time(series[index], column, scene if joules else None) if index in series else None
        if values is None:
            continue
        # a log axis has no zero: the start (where every error is 0) and exact samples are left out
        values = values.abs()
        values = values[(values.index > 0) & (values > 0) & np.isfinite(values)]
        if not values.empty:
            lines[index] = values
    if not lines:
        return None
    fig = one_line_per_engine(rows, lines, "lines")
    if joules:
        title, axis, question = "Energy gained or lost |E − E₀| (J)", "|E − E₀| (J)", QUESTIONS["energy_joules"]
    elif column in ("stack_drift", "penetration"):
        axis = f"{title.split(':')[0].split(' (')[0].lower()} ({unit})"
    elif column == "energy_drift":
        axis = "|E − E₀| / energy in play"
    else:
        axis = f"{title.split(' ')[0].lower()} error ({unit})" if unit else "relative drift"
    fig.update_layout(title=title, xaxis_title="time (s)", yaxis_title=axis)
    fig.update_yaxes(type="log", exponentformat="power")
    return dict(question=question if joules else QUESTIONS.get(column, ""), html=figure_html(fig))


def at_own_knobs(rows: pd.DataFrame) -> pd.DataFrame:
    """The rows run at their engine's own substeps and iterations (none swept), or all of them
    when every row swept a knob."""
    knobs = [c for c in ("substeps", "iterations") if c in rows]
    own = rows[rows[knobs].isna().all(axis=1)] if knobs else rows
    return own if len(own) else rows


# a time series longer than this is drawn as this many equal spans of time, each its largest value;
# a variant behind the legend (a click away, drawn by the few who ask) with fewer
DRAWN_SPANS = 150
HIDDEN_SPANS = 50


def drawn_points(values: pd.Series, spans: int = DRAWN_SPANS) -> dict:
    """A line chart's x and y for `values` (sorted by its index) at a page's width, as float32
    (which a chart a few hundred pixels high cannot tell from float64): a short series whole; a
    longer one as `spans` equal spans of its time, each drawn at its middle with its largest value
    (the worst error in it, so every peak is drawn), a span without samples left a gap. Evenly
    spaced x is given as a start and a step instead of an array."""
    t = values.index.to_numpy(float)
    if len(values) <= spans:
        y = values.to_numpy(np.float32)
        step = np.diff(t)
        if len(t) > 2 and np.allclose(step, step[0], rtol=1e-6, atol=0):
            return dict(x0=float(t[0]), dx=float(step[0]), y=y)
        return dict(x=t.astype(np.float32), y=y)
    width = (t[-1] - t[0]) / spans
    which = np.minimum(((t - t[0]) / width).astype(int), spans - 1)
    top = np.full(spans, np.nan)
    np.fmax.at(top, which, values.to_numpy(float))
    return dict(x0=float(t[0] + width / 2), dx=float(width), y=top.astype(np.float32))


def one_line_per_engine(rows: pd.DataFrame, lines: dict, mode: str) -> go.Figure:
    """A figure of each row's series (lines: row index → a Series against its x), each engine's
    default among the runs drawn shown and every other variant behind the legend, so that every
    engine with a line shows one."""
    shown = default_labels(rows.loc[list(lines)])
    fig = go.Figure()
    for index, values in lines.items():
        label = rows.at[index, "label"]
        visible = label in shown
        fig.add_trace(go.Scatter(**drawn_points(values, DRAWN_SPANS if visible else HIDDEN_SPANS), mode=mode,
                                 name=label, visible=True if visible else "legendonly", **trace_style(label)))
    return fig


def error_by_body(rows: pd.DataFrame, series: dict) -> dict | None:
    """Max position error of each probed body over the run, against its index: how error grows
    along a chain, one line per engine shown (its default variant), the others behind the legend.
    Only for scenes with more than one probed body and a reference."""
    lines = {}
    for index in rows.index:
        traj = series.get(index)
        if traj is None or "body_position_err" not in traj or traj["body"].nunique() < 2:
            continue
        per_body = traj.groupby("body", sort=True)["body_position_err"].max()
        per_body = per_body[per_body > 0]  # a log axis has no zero
        if not per_body.empty:
            lines[index] = per_body
    if not lines:
        return None
    fig = one_line_per_engine(rows, lines, "lines+markers")
    fig.update_layout(title="Max position error of each body (body index along the scene)",
                      xaxis_title="body (index in the scene)", yaxis_title="max position error (m)")
    fig.update_yaxes(type="log", exponentformat="power")
    return dict(question="How does the error grow along the chain, body by body?", html=figure_html(fig))


def throughput_chart(rows: pd.DataFrame) -> dict | None:
    """Median steps/s of every engine variant at the scene's own step, bars from min to max."""
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
    return dict(question="How many steps per second does each engine variant take?", html=figure_html(fig))


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


def scene_of(folder: Path, info: dict) -> dict | None:
    """The scene file a scenario ran at its own step (scenes/*.json), or None when it is absent."""
    own = info.get("dt")
    for dt, path in (info.get("scene_file") or {}).items():
        if (own is None or abs(float(dt) - own) <= 1e-6 * own) and (folder / path).is_file():
            return json.loads((folder / path).read_text())
    return None


def scenario_sections(folder: Path, results: pd.DataFrame, meta: dict, replays: dict,
                      replayed_above: set[str] = frozenset()) -> list[dict]:
    """Each scenario's section but the family members', in the order of results.csv: its
    description, reference, contact table, replay (replays: replay.replays; those in
    replayed_above are drawn higher up the page, and linked) and charts, each with its question,
    the charts over time drawn at the scene's own step, speed against error over the whole sweep."""
    family = drawn_as_family(results, meta)
    sections = []
    for name, rows in results.groupby("scenario", sort=False):
        info = meta.get("scenarios", {}).get(name, {})
        if name in family:
            continue
        own = rows[[is_nominal(meta, r) for _, r in rows.iterrows()]]
        # the charts over time draw each configuration at its engine's own knobs; the swept
        # substeps and iterations are the fronts' and the best-knobs table's
        drawn = at_own_knobs(own)
        series = trajectories(folder, drawn)
        # a contact scene's energy in joules, from its scene's masses and shapes
        scene = scene_of(folder, info) if has_contact_metrics(own) else None
        charts = [error_over_time(drawn, series, column, title, unit, scene) for column, title, unit, summary in SERIES
                  if summary in drawn and drawn[summary].notna().any()]
        charts += [error_by_body(drawn, series), throughput_chart(own)]
        del series  # the next scenario's trajectories take their place
        self_errors = info.get("reference_self_error")
        floors = {float(k): v for k, v in self_errors.items()} if isinstance(self_errors, dict) else None
        chart, front = speed_error(rows, floors)
        if chart:
            charts.append(dict(question="Which engine and step give the least error for the time they take?",
                               html=chart))
        self_error = reference_error(info)
        sweep = sorted(info.get("sweep_dt", []))
        sections.append(dict(
            name=name, anchor=anchor_of(name), description=info.get("description", ""), question=info.get("question", ""),
            dt=fmt(info.get("dt")), duration=fmt(info.get("duration")), reference=info.get("reference", ""),
            self_error=fmt(self_error) if self_error is not None else "",
            reference_failures=[dict(dt=fmt(float(dt)), why=why)
                                for dt, why in (info.get("reference_failure") or {}).items()],
            sweep=", ".join(f"1/{1 / dt:.0f}" for dt in sweep) if len(sweep) > 1 else "",
            charts=[c for c in charts if c], front=front, contact=contact_table(own),
            replay=None if name in replayed_above else replays.get(name), replayed_above=name in replayed_above,
            unsupported=[f"{r['label']}: {r['message']}" for _, r in own.iterrows() if r["status"] == "unsupported"]))
    return sections
