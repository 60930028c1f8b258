"""The page's first screen (each engine's own Pareto front per key question), the scoreboard, and
the charts over time: one visible line per engine, log axes from the first sample after the start,
a contact scene's energy in joules."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

import support  # noqa: F401  (puts the report modules on the path)
from physbench_report import front, glance, scenarios

TOWER = {"scenarios": {"tower-10": {"dt": 1 / 60}}}


def stack_row(engine, variant, ms, drift, verdict="stands", status="ok", substeps=float("nan")):
    label = f"{engine}/{variant}" + (f" substeps={int(substeps)}" if substeps == substeps else "")
    return dict(scenario="tower-10", engine=engine, variant=variant, label=label, status=status, dt=1 / 60,
                duration=10.0, steps_per_s=1e3 / ms if status == "ok" else float("nan"),
                wall_s_median=ms * 0.6 if status == "ok" else float("nan"),
                stack_drift_max=drift if status == "ok" else float("nan"),
                contact_verdict=verdict if status == "ok" else None, substeps=substeps, message="")


def tower_rows() -> pd.DataFrame:
    return pd.DataFrame([
        stack_row("bullet", "float", 0.2, 30.0, verdict="collapsed"),  # bullet's fastest: collapsed
        stack_row("bullet", "float", 4.0, 0.005, substeps=4),
        stack_row("bullet", "double", 2.0, 0.008),                   # beaten by rtp, not by bullet's own
        stack_row("bullet", "double", 3.0, 0.009),                   # beaten by bullet/double at 2 ms
        stack_row("rtp", "soft-step", 1.0, 1e-3),
        stack_row("rtp", "soft-step-2t", 0.5, 1e-3),                 # two threads: no part in a front
        stack_row("rtp", "seed", 0.3, 1e-4, verdict="sinks"),         # the least drift, but it sank
        stack_row("ode", "quickstep", 0.0, 0.0, status="exploded"),
        stack_row("jolt", "default", 0.4, 0.05, verdict="drifts"),
    ])


def test_each_engines_front_holds_only_its_runs_that_passed():
    fronts = front.engine_fronts(front.stack_points(tower_rows(), TOWER))
    labels = {engine: list(f["label"]) for engine, f in fronts.items()}
    # bullet's collapsed run is its fastest, and rtp's sunk run drifts least: neither is on a front
    assert labels == {"bullet": ["bullet/double", "bullet/float substeps=4"], "rtp": ["rtp/soft-step"]}
    # one front an engine, not one for all: rtp's run beats bullet/double on both, which stays on bullet's
    assert list(fronts["bullet"]["cost"]) == pytest.approx([2.0, 4.0])


def test_the_stacking_chart_draws_a_line_per_engine_with_rtp_marked(monkeypatch):
    monkeypatch.setattr(front, "figure_html", lambda fig, **_: fig)  # the figure, not its HTML
    screen = front.first_screen(tower_rows(), TOWER)
    (chart,) = screen["charts"]
    assert chart["topic"] == "stacking" and chart["question"].endswith("?")
    fig = chart["chart"]
    assert [t.name for t in fig.data] == ["bullet", "rtp"]  # rtp drawn last, over its peers
    drawn = [label for t in fig.data for label, _ in t.customdata]
    assert "bullet/float" not in drawn and "rtp/seed" not in drawn and "jolt/default" not in drawn
    bullet, rtp = fig.data
    assert rtp.marker.symbol == "star" and rtp.line.width > bullet.line.width and rtp.line.color != bullet.line.color
    assert fig.layout.xaxis.title.text == "ms per step, median" and fig.layout.yaxis.title.text == "max drift (m)"
    # the engines with no run that passed are named under the chart
    assert "no run passed: ode, jolt" in chart["note"]
    assert [e["name"] for e in screen["engines"]] == ["rtp", "bullet"]


def free_row(engine, variant, dt, cost, error, status="ok"):
    return dict(scenario="tumbling-box", engine=engine, variant=variant, label=f"{engine}/{variant}", status=status,
                dt=dt, duration=1.0, steps_per_s=1 / (dt * cost), wall_s_median=cost, orientation_err_max=error)


def test_an_error_question_reads_every_step_of_the_sweep_and_leaves_out_diverged_runs(monkeypatch):
    monkeypatch.setattr(front, "figure_html", lambda fig, **_: fig)
    rows = pd.DataFrame([
        free_row("rtp", "rk4", 1 / 30, 1e-4, 1e-3), free_row("rtp", "rk4", 1 / 60, 2e-4, 6e-5),
        free_row("rtp", "euler", 1 / 30, 5e-5, 0.1),
        free_row("rtp", "midpoint", 1 / 30, 1e-5, 1e-9, status="diverged"),
        free_row("mujoco", "euler", 1 / 60, 1e-4, 1e-2),
    ])
    (chart,) = front.first_screen(rows, {"scenarios": {"tumbling-box": {"dt": 1 / 60}}})["charts"]
    assert chart["topic"] == "free motion"
    rtp = next(t for t in chart["chart"].data if t.name == "rtp")
    assert [label for label, _ in rtp.customdata] == ["rtp/euler", "rtp/rk4", "rtp/rk4"]
    assert chart["chart"].layout.yaxis.title.text == "max orientation error (rad)"


def test_the_scoreboard_names_the_fastest_that_passed_and_the_failures_in_few_words():
    rows = tower_rows()
    (entry,) = glance.at_a_glance(rows, TOWER)
    # bullet collapsed fastest, rtp/seed sank: the fastest that passed is rtp's two-thread soft step
    assert entry["fastest"].startswith("rtp/soft-step-2t (")
    assert entry["accurate"].startswith("rtp/soft-step")
    texts = [f["text"] for f in entry["failures"]]
    # one step only: no dt in the words
    assert texts == ["bullet/float collapsed", "rtp/seed sinks", "ode/quickstep exploded", "jolt/default drifts"]
    assert all(f["why"] for f in entry["failures"])


def test_a_swept_scenarios_failures_say_at_which_steps():
    rows = pd.DataFrame([free_row("rtp", "euler", 1 / 30, 1e-5, 1.0, status="diverged"),
                         free_row("rtp", "euler", 1 / 60, 1e-5, 1.0, status="diverged"),
                         free_row("rtp", "rk4", 1 / 60, 1e-4, 1e-4)])
    rows["message"] = ["energy grew", "energy grew", ""]
    (entry,) = glance.at_a_glance(rows, {"scenarios": {"tumbling-box": {"dt": 1 / 60}}})
    assert [f["text"] for f in entry["failures"]] == ["rtp/euler diverged at dt = 0.0333, 0.0167 s"]
    assert entry["failures"][0]["why"] == "energy grew"


def trajectory(times, column, values, body=1) -> pd.DataFrame:
    return pd.DataFrame({"time": times, "body": body, column: values})


def test_a_chart_over_time_shows_one_line_per_engine_and_starts_after_the_start(monkeypatch):
    monkeypatch.setattr(scenarios, "figure_html", lambda fig: fig)
    rows = pd.DataFrame([stack_row("rtp", "seed", 1.0, 1e-3), stack_row("rtp", "soft-step", 1.0, 1e-3),
                         stack_row("bullet", "double", 1.0, 1e-3), stack_row("bullet", "float", 1.0, 1e-3),
                         stack_row("bullet", "float", 1.0, 1e-3, substeps=4)])
    times = [0.0, 1 / 60, 2 / 60, 3 / 60]
    series = {i: trajectory(times, "stack_drift", [0.0, 0.0, 1e-3, 2e-3]) for i in rows.index}
    chart = scenarios.error_over_time(rows, series, "stack_drift", "Stack drift: largest horizontal displacement",
                                      "m")
    fig = chart["html"]
    assert chart["question"].endswith("?")
    visible = [t.name for t in fig.data if t.visible is True]
    assert visible == ["rtp/soft-step", "bullet/float"]  # each engine's default variant
    assert all(t.visible == "legendonly" for t in fig.data if t.name not in visible)
    assert len(fig.data) == len(rows)  # the others a click away
    # no t = 0 and no zero on the log axis: the line starts at its first positive sample
    assert list(fig.data[0].x) == pytest.approx([2 / 60, 3 / 60]) and min(fig.data[0].y) > 0
    assert fig.layout.yaxis.type == "log" and fig.layout.yaxis.title.text == "stack drift (m)"
    assert fig.layout.xaxis.title.text == "time (s)"


def box_state(time, y, vy, w, q, body=1) -> dict:
    return dict(time=time, body=body, px=0.0, py=y, pz=0.0, qw=q[0], qx=q[1], qy=q[2], qz=q[3], vx=0.0, vy=vy,
                vz=0.0, wx=w[0], wy=w[1], wz=w[2], energy_drift=1e12)  # a relative drift: not what is drawn


def test_a_contact_scenes_energy_is_the_joules_gained_or_lost(monkeypatch):
    monkeypatch.setattr(scenarios, "figure_html", lambda fig: fig)
    scene = {"gravity": [0.0, -9.81, 0.0],
             "bodies": [{"mass": 0.0, "shape": {"type": "plane"}},
                        {"mass": 2.0, "shape": {"type": "box", "half_extents": [1.0, 0.5, 0.25]}}]}
    turned = (math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0)  # 90° about y: world z is body −x
    traj = pd.DataFrame([box_state(0.0, 1.0, 0.0, (0, 0, 0), (1, 0, 0, 0)),
                         box_state(0.1, 0.9, -1.0, (0, 0, 0), (1, 0, 0, 0)),
                         box_state(0.2, 0.8, -2.0, (0, 0, 1.0), turned)])
    # E = ½ m v² + ½ ωᵀ R I Rᵀ ω − m g·x; spinning about body x, I_x = m (0.5² + 0.25²) / 3
    e0 = 2 * 9.81 * 1.0
    e1 = 0.5 * 2 * 1.0 + 2 * 9.81 * 0.9
    e2 = 0.5 * 2 * 4.0 + 0.5 * (2 / 3 * (0.25 + 0.0625)) + 2 * 9.81 * 0.8
    energy = scenarios.mechanical_energy(traj, scene)
    assert list(energy.values) == pytest.approx([e0, e1, e2])
    rows = pd.DataFrame([stack_row("rtp", "soft-step", 1.0, 1e-3)])
    chart = scenarios.error_over_time(rows, {0: traj}, "energy_drift", "Relative energy drift", "", scene)
    fig = chart["html"]
    (trace,) = fig.data
    # lost 0.96 J, then gained 0.18 J: both drawn as their size in joules, from t > 0
    assert list(trace.x) == pytest.approx([0.1, 0.2])
    assert list(trace.y) == pytest.approx([e0 - e1, e2 - e0])
    assert fig.layout.yaxis.type == "log" and "(J)" in fig.layout.yaxis.title.text
    assert "E − E₀" in fig.layout.title.text and "joules" in chart["question"]


def test_springs_count_in_a_scenes_energy():
    scene = {"gravity": [0.0, 0.0, 0.0], "bodies": [{"mass": 1.0, "shape": {"type": "sphere", "radius": 0.1}}],
             "springs": [{"body_a": 0, "body_b": -1, "point_b": [0, 0, 0], "stiffness": 100.0, "rest_length": 0.5}]}
    traj = pd.DataFrame([dict(box_state(0.0, 1.0, 0.0, (0, 0, 0), (1, 0, 0, 0), body=0)),
                         dict(box_state(0.5, 0.7, 0.0, (0, 0, 0), (1, 0, 0, 0), body=0))])
    energy = scenarios.mechanical_energy(traj, scene)
    assert list(energy.values) == pytest.approx([0.5 * 100 * 0.5 ** 2, 0.5 * 100 * 0.2 ** 2])


def test_a_log_chart_over_time_never_draws_a_zero_or_a_non_finite_value(monkeypatch):
    monkeypatch.setattr(scenarios, "figure_html", lambda fig: fig)
    rows = pd.DataFrame([free_row("rtp", "rk4", 1 / 60, 1e-4, 1e-3)])
    traj = trajectory([0.0, 0.1, 0.2, 0.3, 0.4], "position_err", [0.0, 1e-6, 0.0, np.inf, 3e-6])
    fig = scenarios.error_over_time(rows, {0: traj}, "position_err", "Position error against the reference",
                                    "m")["html"]
    assert list(fig.data[0].x) == pytest.approx([0.1, 0.4]) and list(fig.data[0].y) == pytest.approx([1e-6, 3e-6])
    assert fig.layout.yaxis.title.text == "position error (m)"


def test_the_benchmarks_broad_and_narrow_phase_join_the_first_screen_where_the_run_has_them(monkeypatch):
    monkeypatch.setattr(front, "figure_html", lambda fig, **_: fig)
    broad = {"rows": [dict(motion="coherent", boxes=1000, engine="rtp/box-pruning", us=50.0),
                      dict(motion="coherent", boxes=10000, engine="rtp/box-pruning", us=600.0),
                      dict(motion="coherent", boxes=1000, engine="bullet/dbvt", us=400.0),
                      dict(motion="random", boxes=1000, engine="bullet/dbvt", us=900.0)]}
    narrow = {"rows": [dict(set="box-box/touching", engine="rtp/sat", ns=100.0),
                       dict(set="box-box/touching", engine="bullet/box-box", ns=150.0)]}
    screen = front.first_screen(tower_rows(), TOWER, broad, narrow)
    assert [c["topic"] for c in screen["charts"]] == ["stacking", "broad phase", "narrow phase"]
    broadphase, narrowphase = screen["charts"][1]["chart"], screen["charts"][2]["chart"]
    # coherent motion only, rtp drawn last and starred, each in its engine's hue
    assert [(t.name, list(t.x)) for t in broadphase.data] == [("bullet/dbvt", [1000]),
                                                             ("rtp/box-pruning", [1000, 10000])]
    assert broadphase.data[1].marker.symbol == "star" and broadphase.data[1].line.color == front.hue("rtp")
    assert [t.name for t in narrowphase.data] == ["bullet/box-box", "rtp/sat"]
    assert broadphase.layout.yaxis.title.text == "µs per update, median"
    assert narrowphase.layout.xaxis.title.text == "ns per pair, median"
    assert all(c["question"].endswith("?") for c in screen["charts"])
    # without the benchmark files, no such chart
    assert [c["topic"] for c in front.first_screen(tower_rows(), TOWER)["charts"]] == ["stacking"]


def test_rtp_at_the_baseline_instruction_set_is_a_front_of_its_own():
    # a front mixing rtp's two builds would hide the baseline build behind the native one: the
    # baseline rows become rtp-x86-64, and two-thread rows take no part
    from physbench_report.front import engine_fronts, one_thread

    rows = pd.DataFrame([
        dict(engine="rtp", variant="soft-step", label="rtp/soft-step", cost=1.0, error=1e-3, dt=1 / 60),
        dict(engine="rtp", variant="soft-step-2t", label="rtp/soft-step-2t", cost=0.5, error=1e-3, dt=1 / 60),
        dict(engine="rtp", variant="soft-step-x86-64", label="rtp/soft-step-x86-64", cost=3.0, error=1e-3,
             dt=1 / 60),
        dict(engine="bullet", variant="float", label="bullet/float", cost=2.0, error=1e-2, dt=1 / 60),
    ])
    fronts = engine_fronts(one_thread(rows))
    assert set(fronts) == {"rtp", "rtp-x86-64", "bullet"}
    assert list(fronts["rtp"]["label"]) == ["rtp/soft-step"]
    assert list(fronts["rtp-x86-64"]["label"]) == ["rtp/soft-step-x86-64"]


def test_a_long_series_is_drawn_as_its_largest_value_in_each_span_and_a_short_one_whole():
    t = np.arange(1, 1001) / 100.0  # 10 s, a sample every 0.01 s
    y = np.full(1000, 1e-6)
    y[537] = 3e-2  # one spike: it must be drawn, at its height
    y[800:850] = np.nan  # dropped samples (zeros on a log axis) leave a gap, not a line through them
    drawn = scenarios.drawn_points(pd.Series(y, index=t), spans=100)
    assert "x" not in drawn and drawn["x0"] == pytest.approx(t[0] + 0.0999 / 2) and drawn["dx"] == pytest.approx(0.0999)
    assert len(drawn["y"]) == 100 and drawn["y"].dtype == np.float32
    assert np.nanmax(drawn["y"]) == pytest.approx(3e-2) and np.nanargmax(drawn["y"]) == int((t[537] - t[0]) / 0.0999)
    # spans 80 to 84 (8.002 to 8.5015 s) hold only dropped samples (8.01 to 8.50 s)
    assert list(np.flatnonzero(np.isnan(drawn["y"]))) == [80, 81, 82, 83, 84]
    # a short, evenly spaced series keeps every sample, its x a start and a step
    short = scenarios.drawn_points(pd.Series([1.0, 2.0, 3.0], index=[0.5, 1.0, 1.5]), spans=100)
    assert short["x0"] == 0.5 and short["dx"] == pytest.approx(0.5) and list(short["y"]) == [1.0, 2.0, 3.0]
    uneven = scenarios.drawn_points(pd.Series([1.0, 2.0, 3.0], index=[0.5, 1.0, 2.5]), spans=100)
    assert list(uneven["x"]) == [0.5, 1.0, 2.5]


def test_the_charts_over_time_draw_each_engine_at_its_own_knobs():
    rows = pd.DataFrame([stack_row("rtp", "soft-step", 1.0, 1e-3), stack_row("bullet", "float", 1.0, 1e-3),
                         stack_row("bullet", "float", 2.0, 1e-4, substeps=4)])
    assert list(scenarios.at_own_knobs(rows).index) == [0, 1]
    swept = rows.iloc[[2]]
    assert list(scenarios.at_own_knobs(swept).index) == [2]  # nothing at its own knobs: what there is
