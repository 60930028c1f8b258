"""The report builder on a real results folder written by physbench."""
from __future__ import annotations

import html
import os
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from support import PHYSBENCH, figure_specs, physbench_run, readable
import build_report  # noqa: E402  (found through support's path)
from physbench_report import benchmarks, contacts, glance, load, profile, speed, table  # noqa: E402


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> Path:
    # a short sweep keeps the converged references cheap
    return physbench_run(tmp_path_factory.mktemp("run") / "r", "-s", "projectile,projectile-planar,tumbling-box",
                         "--sweep-hz", "30,60,120")


def test_report_is_self_contained_and_names_every_row(results):
    page = readable(build_report.build_report(results).read_text())
    # opens offline: no script or stylesheet fetched from anywhere
    assert not re.search(r"<script[^>]+src=", page)
    assert not re.search(r"<link[^>]+href=\"http", page)
    assert "Plotly" in page
    table = pd.read_csv(results / "results.csv")
    for _, row in table.iterrows():
        assert f"{row['engine']}/{row['variant']}" in page
    for scenario in table["scenario"].unique():
        assert f"<h2>{scenario}</h2>" in page


def test_every_scenario_has_error_and_throughput_charts(results, monkeypatch):
    # each trajectory is read once, however many of its scenario's charts draw from it
    reads, read_csv = [], pd.read_csv

    def counted(path, *args, **kwargs):
        reads.append(Path(path))
        return read_csv(path, *args, **kwargs)
    monkeypatch.setattr(pd, "read_csv", counted)
    page = readable(build_report.build_report(results).read_text())
    trajectories = [path for path in reads if path.parent.name == "trajectories"]
    assert trajectories and len(trajectories) == len(set(trajectories))
    # each scenario's section carries its anchor (the front page's contents link to it)
    sections = [s.split("</section>")[0] for s in page.split('<section id="s-')[1:]]
    assert len(sections) == 3
    for section in sections:
        assert "Throughput" in section
        assert "error against the reference" in section or "drift" in section
    assert "Orientation error against the reference" in page  # tumbling-box's converged reference


def test_settings_tables_reach_the_report(results):
    page = readable(build_report.build_report(results).read_text())
    engines = set(pd.read_csv(results / "results.csv")["engine"])
    assert "momentum form" in page              # rtp's integrator setting
    if "bullet" in engines:
        assert "DISABLE_DEACTIVATION" in page  # Bullet's sleeping switch
    if "ode" in engines:
        assert "dRandSetSeed" in page          # ODE's seeding


def test_unsupported_rows_show_their_reason(results):
    table = pd.read_csv(results / "results.csv")
    unsupported = table[table["status"] == "unsupported"]
    if unsupported.empty:
        pytest.skip("this build has no engine that refuses one of these scenes")
    page = readable(build_report.build_report(results).read_text())
    for message in unsupported["message"]:
        assert html.escape(message) in page


def test_full_table_has_every_run_at_its_own_step_with_values_to_sort_by(results):
    frame, meta = load.load_results(results)
    full = table.results_table(frame, meta)
    own = pd.read_csv(results / "results.csv")
    own = own[(own["dt"] - 1 / 60).abs() < 1e-9]  # --sweep-hz 30,60,120: the scenes' own step is 1/60
    assert [(r["engine"], r["status"]) for r in full["rows"]] == list(zip(own["engine"], own["status"]))
    assert set(full["engines"]) == set(own["engine"]) and set(full["statuses"]) == set(own["status"])
    # each number cell sorts by its full value, not its rounded text; an empty cell by nothing
    steps = full["columns"].index("steps/s (median)")
    for row, (_, expected) in zip(full["rows"], own.iterrows()):
        text, value = row["numbers"][steps]
        if pd.isna(expected["steps_per_s"]):
            assert (text, value) == ("", "")
        else:
            assert float(value) == expected["steps_per_s"] and text == build_report.fmt(expected["steps_per_s"])


def test_missing_results_is_a_clear_error(tmp_path):
    with pytest.raises(build_report.ReportError, match="results.csv: missing"):
        build_report.build_report(tmp_path)
    assert build_report.main([str(tmp_path)]) == 2
    assert not (tmp_path / "index.html").exists()


def test_broken_metadata_is_named(results, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(results, copy)
    (copy / "metadata.json").write_text("{ not json")
    with pytest.raises(build_report.ReportError, match="metadata.json: not valid JSON"):
        build_report.build_report(copy)


def test_swept_scenario_gets_a_pareto_front_and_measured_orders(results):
    page = readable(build_report.build_report(results).read_text())
    tumbling = page.split("<h2>tumbling-box</h2>")[1].split("<section>")[0]
    assert "Pareto front: nothing else is both faster and more accurate" in tumbling
    # legend names live in the plotly JSON, where "/" is written \u002f
    assert re.search(r"rtp(/|\\u002f)rk4 \(order [0-9.]+\)", tumbling)


def test_convergence_order_and_front_on_known_points():
    points = pd.DataFrame({"dt": [0.1, 0.05, 0.025], "err": [1.0, 1 / 16, 1 / 256]})
    assert speed.convergence_order(points, "err") == pytest.approx(4.0)
    # fewer than three steps measure no order
    assert speed.convergence_order(points.iloc[:2], "err") is None
    # points at the reference's own error floor are left out of the fit
    floored = pd.DataFrame({"dt": [0.1, 0.05, 0.025, 0.0125], "err": [1.0, 1 / 16, 1 / 256, 1 / 300]})
    assert speed.convergence_order(floored, "err", {0.0125: 1 / 1000}) == pytest.approx(4.0)
    costs = pd.DataFrame({"cost": [1.0, 2.0, 3.0, 4.0], "err": [0.5, 0.6, 0.1, 0.01]})
    front = speed.pareto_front(costs, "err")
    assert list(front["cost"]) == [1.0, 3.0, 4.0]  # (2.0, 0.6) is beaten by (1.0, 0.5)


def test_stability_map_classifies_every_run_of_a_family(tmp_path):
    if not PHYSBENCH:
        pytest.skip("PHYSBENCH_EXE is not set (CTest sets it)")
    out = tmp_path / "r"
    subprocess.run([PHYSBENCH, "run", "-s", "stiff-spring-k1e2,stiff-spring-k1e4", "-e", "rtp", "--budget", "0",
                    "--out", str(out)], check=True, capture_output=True)
    page = readable(build_report.build_report(out).read_text())
    table = page.split("Stability map: stiff-spring")[1].split("</table>")[0]
    # every run of the family has a class: 2 stiffnesses x 4 steps x each rtp variant, and its
    # baseline-ISA build at each scene's own step only (plan.cpp: its accuracy repeats its sibling's)
    cells = re.findall(r'<td class="(stable|unstable|over-damped|exploded)">', table)
    rows = pd.read_csv(out / "results.csv")
    isa = rows["variant"].str.endswith("-x86-64")
    assert len(cells) == len(rows)
    assert len(rows[~isa]) == 2 * 4 * rows[~isa]["variant"].nunique()
    assert (rows[isa].groupby("variant").size() == 2).all()
    # the family's scenarios are not repeated as sections or summary rows
    assert "<h2>stiff-spring-k1e2</h2>" not in page
    # midpoint cannot hold k = 1e4 at dt = 1/30: its cell says so
    midpoint = table.split("rtp/midpoint")[1].split("</tr>")[0]
    assert "exploded" in midpoint or "unstable" in midpoint


def test_particle_benchmark_roofline_reaches_the_scaling_chart(tmp_path):
    if not PHYSBENCH:
        pytest.skip("PHYSBENCH_EXE is not set (CTest sets it)")
    out = tmp_path / "r"
    subprocess.run([PHYSBENCH, "run", "-s", "particles-scaling-10000,particles-scaling-100000", "-e", "rtp",
                    "--budget", "0", "--out", str(out)], check=True, capture_output=True)
    # the shape Google Benchmark's JSON reporter writes, for one triad and one particle run
    (out / "benchmarks").mkdir()
    (out / "benchmarks" / "particles.json").write_text(json.dumps({"context": {"particle_kernels": "avx512"},
                                                                 "benchmarks": [
        {"name": "Triad/1/real_time", "run_type": "iteration", "threads": 1, "bytes_per_second": 3.0e10},
        {"name": "ParticleUpdate/particles:100000/threads:1/real_time", "run_type": "iteration",
         "items_per_second": 5.0e7, "bytes_per_particle_step": 60, "roofline_fraction": 0.1},
        {"name": "ThreadsPaired/particles:4000000/iterations:40/manual_time", "run_type": "iteration",
         "particles": 4e6, "rounds": 40, "one_thread_ms": 20.0, "two_threads_ms": 11.0, "speedup": 1.818,
         "speedup_least_block": 1.7, "speedup_largest_block": 1.9, "blocks": 5},
    ]}))
    page = readable(build_report.build_report(out).read_text())
    assert "Scaling: particles-scaling" in page
    assert "roofline, 1 thread(s)" in page
    assert "<td>100000</td><td>1</td><td>5e+07</td>" in page
    assert "attractor mode, avx512 kernels)" in page
    assert "<td>4000000</td><td>40</td><td>20.00</td><td>11.00</td>\n<td>1.82× (1.70–1.90)</td><td>5</td>" in page
    # 5e7 particle-steps/s at 60 steps/s: 8.3e5 particles, more than the 1e5 measured
    assert "holds 8.3e+05 particles\non 1 thread(s) (extrapolated from 100000" in page


def test_broadphase_benchmark_reaches_the_report(tmp_path):
    if not PHYSBENCH:
        pytest.skip("PHYSBENCH_EXE is not set (CTest sets it)")
    out = tmp_path / "r"
    subprocess.run([PHYSBENCH, "run", "-s", "projectile", "-e", "rtp", "--no-sweep", "--budget", "0",
                    "--out", str(out)], check=True, capture_output=True)
    (out / "benchmarks").mkdir()

    def update(engine, boxes, aggregate, real_time, **counters):
        return dict(name=f"Update/coherent/{boxes}/{engine}/real_time_{aggregate}", run_type="aggregate",
                    run_name=f"Update/coherent/{boxes}/{engine}/min_time:0.100/repeats:3/real_time",
                    aggregate_name=aggregate, real_time=real_time, time_unit="us", **counters)

    counters = dict(items_per_second=1e6, exact_pairs=500, missing_pairs=0, extra_pairs_fraction=0.3)
    (out / "benchmarks" / "broadphase.json").write_text(json.dumps({
        "context": {"settings bullet/dbvt": "3.24 (float); broadphase=btDbvtBroadphase (default)"},
        "benchmarks": [
            update("rtp/box-pruning", 1000, "median", 50.0, **counters),
            update("rtp/box-pruning", 1000, "cv", 0.021),
            update("bullet/dbvt", 1000, "median", 400.0, **counters),
            {"name": "Paired/coherent/10000/bullet/dbvt/iterations:400/manual_time", "run_type": "iteration",
             "run_name": "Paired/coherent/10000/bullet/dbvt/iterations:400/manual_time", "real_time": 7000.0,
             "time_unit": "us", "rounds": 400, "rtp_us": 640.0, "peer_us": 6912.0, "ratio": 10.8,
             "ratio_least_block": 10.25, "ratio_largest_block": 11.5, "blocks": 8},
            {"name": "Build/coherent/50000/rtp/box-pruning/real_time", "run_type": "iteration",
             "run_name": "Build/coherent/50000/rtp/box-pruning/min_time:0.100/real_time", "real_time": 12.5,
             "time_unit": "ms"},
        ]}))
    page = readable(build_report.build_report(out).read_text())
    assert "<h2>Broad phase</h2>" in page
    # rtp's row carries the ratio to the fastest peer of its case: 400 / 50
    assert "8.0×" in page
    # the coefficient of variation in percent
    assert "<td>2.1</td>" in page
    assert "btDbvtBroadphase" in page
    assert "<td>12.5</td>" in page
    # the paired row: its ratio and the spread over blocks, not mixed into the update rows
    assert "<td>10.80×</td><td>10.25–11.50</td>" in page
    assert "<td>6912</td><td>640</td>" in page
    assert "(8 blocks)" in page


def test_narrowphase_benchmark_rows_carry_time_per_pair_and_agreement(tmp_path):
    (tmp_path / "benchmarks").mkdir()

    def pairs(engine, aggregate, real_time, **counters):
        return dict(name=f"Pairs/box-box/touching/{engine}/min_time:0.100/repeats:3_{aggregate}",
                    run_name=f"Pairs/box-box/touching/{engine}/min_time:0.100/repeats:3", run_type="aggregate",
                    aggregate_name=aggregate, real_time=real_time, time_unit="us", **counters)

    (tmp_path / "benchmarks" / "narrowphase.json").write_text(json.dumps({
        "context": {"settings bullet/box-box": "3.24 (float); detector: btBoxBoxDetector",
                    "tolerances": "verdict band 0.001 m"},
        "benchmarks": [
            pairs("rtp/sat", "median", 102.4, pairs=1024),
            pairs("rtp/sat", "cv", 0.012, pairs=0),
            pairs("bullet/box-box", "median", 153.6, pairs=1024, verdict_agreement=1.0, depth_agreement=0.98,
                  normal_agreement=0.99, peer_refuted=3, unexplained=0),
            dict(name="Paired/box-box/deep/bullet/box-box/iterations:200/manual_time", run_type="iteration",
                 run_name="Paired/box-box/deep/bullet/box-box/iterations:200/manual_time", rounds=200,
                 rtp_ns=150.0, peer_ns=300.0, ratio=2.0, ratio_least_block=1.9, ratio_largest_block=2.1, blocks=8,
                 real_time=460.0, time_unit="us"),
        ]}))
    narrow = benchmarks.narrowphase_benchmark(tmp_path)
    by_engine = {r["engine"]: r for r in narrow["rows"]}
    # 102.4 µs over 1024 pairs is 100 ns a pair; Bullet's 150 ns is 1.5 times rtp's
    assert by_engine["rtp/sat"]["ns"] == pytest.approx(100.0)
    assert by_engine["rtp/sat"]["cv"] == pytest.approx(1.2)
    assert by_engine["bullet/box-box"]["vs_rtp"] == pytest.approx(1.5)
    assert by_engine["bullet/box-box"]["peer_refuted"] == 3
    assert narrow["tolerances"] == "verdict band 0.001 m"
    assert "btBoxBoxDetector" in narrow["settings"]["bullet/box-box"]
    # the paired rounds are their own table, not a row of the per-set one
    assert "box-box/deep" not in {r["set"] for r in narrow["rows"]}
    assert narrow["paired"] == [dict(set="box-box/deep", engine="bullet/box-box", rounds=200, rtp_ns=150.0,
                                     peer_ns=300.0, ratio=2.0, least=1.9, largest=2.1, blocks=8)]


def test_particles_at_rate_takes_the_largest_count_per_thread_count():
    rows = [dict(particles=1000, threads=1, steps=1.0e8), dict(particles=4000000, threads=1, steps=6.0e7),
            dict(particles=4000000, threads=2, steps=1.2e9)]
    held = benchmarks.particles_at_rate(rows, 60.0)
    assert [h["threads"] for h in held] == [1, 2]
    assert held[0]["particles"] == pytest.approx(1.0e6) and not held[0]["extrapolated"]
    assert held[1]["particles"] == pytest.approx(2.0e7) and held[1]["extrapolated"]


def test_chain_gets_an_error_per_body_chart(tmp_path):
    if not PHYSBENCH:
        pytest.skip("PHYSBENCH_EXE is not set (CTest sets it)")
    out = tmp_path / "r"
    subprocess.run([PHYSBENCH, "run", "-s", "spring-chain", "--no-sweep", "-e", "rtp", "--variant", "euler",
                    "--budget", "0", "--out", str(out)], check=True, capture_output=True)
    trajectory = pd.read_csv(next((out / "trajectories").glob("*.csv")))
    errors = trajectory.groupby("body")["body_position_err"].max()
    assert len(errors) == 8 and errors.notna().all()
    # the worst body's error is the scenario's position error
    assert errors.max() == pytest.approx(pd.read_csv(out / "results.csv")["position_err_max"].iloc[0], rel=1e-6)
    assert "Max position error of each body" in readable(build_report.build_report(out).read_text())


def test_a_malformed_benchmark_file_is_named(tmp_path):
    (tmp_path / "benchmarks").mkdir()
    (tmp_path / "benchmarks" / "broadphase.json").write_text('{"benchmarks": [')
    with pytest.raises(build_report.ReportError, match="broadphase.json: not valid JSON"):
        benchmarks.broadphase_benchmark(tmp_path)
    assert benchmarks.particle_benchmark(tmp_path) is None  # absent: nothing to draw


@pytest.fixture(scope="module")
def contact_results(tmp_path_factory) -> Path:
    if not PHYSBENCH:
        pytest.skip("PHYSBENCH_EXE is not set (CTest sets it)")
    out = tmp_path_factory.mktemp("contacts") / "r"
    subprocess.run([PHYSBENCH, "run", "-s", "tower-10,bounce-e0.5", "-e", "rtp,box2d,ode", "--budget", "0",
                    "--out", str(out)], check=True, capture_output=True)
    return out


def test_contact_scenes_have_their_tables(contact_results):
    table = pd.read_csv(contact_results / "results.csv")
    ran = table[table["status"] == "ok"]
    if ran.empty:
        pytest.skip("no engine in this build runs contact scenes")
    page = readable(build_report.build_report(contact_results).read_text())
    assert "Contact verdicts" in page
    assert "drift max (m)" in page and "penetration max (m)" in page
    # each engine's own contact count, where it reports one (tower-10: rtp holds 40 points a step)
    assert "contact points a step (the engine&#39;s count)" in page or "contact points a step (the engine's count)" in page
    rtp_tower = ran[(ran["scenario"] == "tower-10") & (ran["engine"] == "rtp") & (ran["variant"] == "soft-step")]
    assert len(rtp_tower) == 1 and rtp_tower["contact_points"].iloc[0] == 40
    assert "Stack drift: largest horizontal displacement" in page  # drift over time
    for _, row in ran[ran["scenario"] == "tower-10"].iterrows():
        assert isinstance(row["contact_verdict"], str) and row["contact_verdict"] in page
    # rtp has no contact solver yet: its rows say why, and the report shows it
    for message in table[table["status"] == "unsupported"]["message"]:
        assert html.escape(message) in page


def test_rtp_stage_profile_is_drawn_from_stage_ms_and_peers_have_none(contact_results):
    table = pd.read_csv(contact_results / "results.csv")
    meta = json.loads((contact_results / "metadata.json").read_text())
    stages = meta["engines"]["rtp"]["stages"]
    assert "solve" in stages and "narrow_phase" in stages
    results, _ = load.load_results(contact_results)
    sections = {p["engine"]: p for p in profile.stage_profiles(results, meta)}
    assert set(sections) == {"rtp"}  # Box2D and ODE do not time their stages: nothing drawn for them
    assert table[table["engine"] != "rtp"]["stage_ms"].isna().all()
    rtp = sections["rtp"]
    ok = table[(table["engine"] == "rtp") & (table["status"] == "ok")]
    assert len(rtp["table"]) == len(ok)
    for row in rtp["table"]:
        shares = [float(v) for v in row["shares"] if v]
        assert len(row["shares"]) == len(stages)
        assert abs(sum(shares) - 100) <= len(shares)  # whole percents of the stages' own sum
    # the soft step's velocity passes are most of a tower step; the seed has no relax at all
    soft = next(r for r in rtp["table"] if r["scenario"] == "tower-10" and r["variant"] == "soft-step")
    share = dict(zip(stages, soft["shares"]))
    assert float(share["solve"]) + float(share["relax"]) > 30
    page = readable(build_report.build_report(contact_results).read_text())
    assert "Where rtp's step goes" in page and 'id="profile-rtp"' in page


def test_knob_swept_rows_are_configurations_of_their_own():
    rows = pd.DataFrame([dict(engine="bullet", variant="float", iterations=float("nan"), substeps=float("nan")),
                         dict(engine="bullet", variant="float", iterations=8.0, substeps=float("nan")),
                         dict(engine="rtp", variant="soft-step", iterations=float("nan"), substeps=2.0)])
    assert [load.knob_suffix(r) for _, r in rows.iterrows()] == ["", " iterations=8", " substeps=2"]
    assert [load.is_swept(r) for _, r in rows.iterrows()] == [False, True, True]


def contact_row(engine, variant, steps_per_s, drift, status="ok", verdict="stands"):
    return dict(scenario="tower-10", engine=engine, variant=variant, label=f"{engine}/{variant}", status=status,
                steps_per_s=steps_per_s if status == "ok" else float("nan"),
                stack_drift_max=drift if status == "ok" else float("nan"),
                contact_verdict=verdict if status == "ok" else "exploded")


def test_drift_against_cost_has_a_front_per_view():
    rows = pd.DataFrame([
        contact_row("rtp", "soft-step", 1000, 1e-3),           # 1 ms
        contact_row("rtp", "sequential-impulse", 2000, 0.05),  # 0.5 ms, beaten by box2d/iterations-10
        contact_row("bullet", "float", 500, 5e-4),             # 2 ms, in both views
        contact_row("ode", "quickstep", 250, 0.01),            # 4 ms, beaten by bullet
        contact_row("ode", "quickstep-10", 0, 0, status="exploded"),
        contact_row("box2d", "default", 10000, 0.1, verdict="settles"),  # 0.1 ms, failed otherwise
        contact_row("box2d", "iterations-10", 8000, 0.02),     # 0.125 ms
        contact_row("rtp", "seed", 1e6, 1e-9),                 # in neither view: must not win one
    ])
    (section,) = contacts.drift_cost_views(rows)
    fronts = {f["view"]: [m.split(" (")[0] for m in f["members"]] for f in section["fronts"]}
    assert fronts["each engine's defaults"] == ["box2d/default", "rtp/soft-step", "bullet/float"]
    assert fronts["equal iterations (10)"] == ["box2d/iterations-10", "bullet/float"]
    assert section["missing"] == ["equal iterations (10): ode/quickstep-10 exploded"]
    drawn = json.dumps(figure_specs(section["chart"]), separators=(",", ":"))
    assert "rtp/seed" not in drawn and "rtp/soft-step" in drawn
    # the settled stack is drawn open, the standing ones filled
    assert drawn.count('"symbol":"circle-open"') == 1
    assert "box2d/default: settles" in drawn


def knob_row(engine, variant, ms, drift, verdict, substeps=float("nan")):
    """A stack row at ms per step, at the variant's own settings or at a swept substep count."""
    r = contact_row(engine, variant, 1e3 / ms, drift, verdict=verdict)
    r.update(substeps=substeps, iterations=float("nan"),
             label=f"{engine}/{variant}" + (f" substeps={int(substeps)}" if substeps == substeps else ""))
    return r


def test_best_configurations_read_every_knob_and_name_the_cheapest_that_stands():
    row = knob_row
    rows = pd.DataFrame([
        row("rtp", "soft-step", 2.0, 1e-3, "stands"),
        row("rtp", "soft-step", 1.25, 2e-3, "stands", substeps=4),
        row("rtp", "soft-step", 0.5, 3.0, "collapsed", substeps=1),
        row("bullet", "float", 1.0, 30.0, "collapsed"),
        row("bullet", "float", 2.0, 0.05, "drifts", substeps=2),
        row("bullet", "float", 4.0, 0.005, "stands", substeps=4),
        row("jolt", "default", 1.0, 20.0, "collapsed"),
    ])
    (section,) = contacts.best_configurations(rows)
    by_engine = {r["engine"]: r for r in section["rows"]}
    assert section["rtp_ms"] == "2"
    assert by_engine["rtp"]["best"] == "rtp/soft-step substeps=4"
    assert by_engine["bullet"]["default"] == "bullet/float: collapsed, 1 ms, drift 30 m"
    assert by_engine["bullet"]["best"] == "bullet/float substeps=4"
    assert by_engine["bullet"]["ratio"] == "3.2"  # 4 ms against rtp's cheapest standing 1.25 ms
    # within rtp's default 2 ms: Bullet's 2-substep row is its least drift
    assert by_engine["bullet"]["within"] == "0.05 m (bullet/float substeps=2)"
    assert by_engine["jolt"]["best"] == "none stands" and by_engine["jolt"]["ratio"] == ""


def test_no_worse_accuracy_reads_every_peer_configuration_against_rtps_cheapest_as_accurate():
    # no configuration stands, so "cheapest that stands" says nothing; the fair reading still does.
    # Box3D's default (2 ms, sinks, 0.28 m) is matched by rtp's 2-substep row (1 ms, sinks, less
    # drift, less top change, less final penetration) but not by its 1-substep row, which is
    # faster but penetrates deeper; Box3D's 8-substep row (4 ms, sinks) is matched by rtp's
    # default (2 ms, settles) and better by its 2-substep row (1 ms); Box3D's collapsing 1-substep
    # row (0.75 ms) by rtp's sinking 1-substep row (0.5 ms), its best showing
    row = knob_row
    rows = pd.DataFrame([
        row("rtp", "soft-step", 2.0, 6e-3, "settles"),
        row("rtp", "soft-step", 1.0, 0.09, "sinks", substeps=2),
        row("rtp", "soft-step", 0.5, 0.20, "sinks", substeps=1),
        row("box3d", "default", 2.0, 0.28, "sinks"),
        row("box3d", "default", 4.0, 0.30, "sinks", substeps=8),
        row("box3d", "default", 0.75, 0.60, "collapsed", substeps=1),
        row("box3d", "default", 9.0, 1e-3, "stands", substeps=16),
    ])
    top = {"rtp/soft-step": -0.04, "rtp/soft-step substeps=2": -0.65, "rtp/soft-step substeps=1": -0.9,
           "box3d/default": -0.72, "box3d/default substeps=8": -0.67, "box3d/default substeps=1": -3.1,
           "box3d/default substeps=16": -1e-3}
    sunk = {"rtp/soft-step": 0.002, "rtp/soft-step substeps=2": 0.015, "rtp/soft-step substeps=1": 0.05,
            "box3d/default": 0.02, "box3d/default substeps=8": 0.035, "box3d/default substeps=1": 0.11,
            "box3d/default substeps=16": 1e-3}
    rows["top_height_change"] = rows["label"].map(top)
    rows["penetration_final"] = rows["label"].map(sunk)
    (section,) = contacts.best_configurations(rows)
    box3d = {r["engine"]: r for r in section["rows"]}["box3d"]
    # the least ratio: the 1-substep row (0.75 ms) against rtp's (0.5 ms); at its defaults 2 ms
    # against rtp's 2-substep 1 ms; and its standing row is one rtp does not match
    assert box3d["matched"] == ("1.5: box3d/default substeps=1 against rtp/soft-step substeps=1; "
                                "at its defaults 2: box3d/default against rtp/soft-step substeps=2; "
                                "none as accurate as box3d/default substeps=16")
    # each measure decides alone: a settled row with more drift than a sinking one is not as accurate
    settles = pd.Series(dict(contact_verdict="settles", stack_drift_max=0.3, top_height_change=-0.01,
                             penetration_final=0.001))
    sinks = pd.Series(dict(contact_verdict="sinks", stack_drift_max=0.28, top_height_change=-0.7,
                           penetration_final=0.02))
    assert not contacts.no_worse(settles, sinks) and not contacts.no_worse(sinks, settles)
    level = settles.copy()
    level["stack_drift_max"] = 0.28
    assert contacts.no_worse(level, sinks) and not contacts.no_worse(sinks, level)


def test_rtp_at_the_baseline_instruction_set_is_read_apart_from_its_native_build():
    # rtp's native build stands at 1 ms, its baseline build (soft-step-x86-64) at 3 ms, Bullet at 2:
    # rtp's own cheapest stays the native one (the baseline row, faster or slower, is never
    # mixed in), the baseline build is a row of its own, and every engine's ratio is given
    # against both builds
    row = knob_row
    rows = pd.DataFrame([
        row("rtp", "soft-step", 1.0, 1e-3, "stands"),
        row("rtp", "soft-step-x86-64", 3.0, 1e-3, "stands"),
        row("rtp", "soft-step-x86-64", 0.5, 2e-3, "stands", substeps=1),
        row("bullet", "float", 2.0, 4e-3, "stands"),
    ])
    (section,) = contacts.best_configurations(rows)
    by_engine = {r["engine"]: r for r in section["rows"]}
    assert section["baseline"] == "rtp-x86-64"
    assert by_engine["rtp"]["best"] == "rtp/soft-step"
    assert by_engine["rtp-x86-64"]["best"] == "rtp/soft-step-x86-64 substeps=1"
    assert by_engine["rtp-x86-64"]["default"].startswith("rtp/soft-step-x86-64: stands, 3 ms")
    assert by_engine["bullet"]["ratio"] == "2"  # 2 ms against the native build's 1 ms
    assert by_engine["bullet"]["ratio_baseline"] == "4"  # against the baseline build's cheapest 0.5 ms


def test_front_page_never_names_a_failed_run_fastest_or_most_accurate():
    # bullet collapses the stack fastest of all, jolt drifts: neither may be named fastest or most
    # accurate; both are failures in words, with their reasons
    rows = pd.DataFrame([
        contact_row("bullet", "float", 5000, 30.0, verdict="collapsed"),
        contact_row("jolt", "default", 4000, 0.2, verdict="drifts"),
        contact_row("rtp", "soft-step", 1000, 1e-3),
        contact_row("ode", "quickstep", 500, 5e-4),
    ])
    rows["dt"], rows["duration"], rows["message"] = 1 / 60, 10.0, ""
    rows["wall_s_median"] = 600 / rows["steps_per_s"]
    rows.loc[0, "message"] = "collapsed: drift 30 m"
    (entry,) = glance.at_a_glance(rows, {"scenarios": {"tower-10": {"dt": 1 / 60}}})
    assert entry["fastest"].startswith("rtp/soft-step")
    assert entry["accurate"].startswith("ode/quickstep")
    assert any(f["text"] == "bullet/float collapsed" and "drift 30 m" in f["why"] for f in entry["failures"])
    assert any(f["text"] == "jolt/default drifts" for f in entry["failures"])


def test_a_scene_without_drift_has_no_drift_chart():
    rows = pd.DataFrame([dict(contact_row("rtp", "soft-step", 1000, 1e-3), stack_drift_max=float("nan"))])
    assert contacts.drift_cost_views(rows) == []


def contacts_json(runs):
    return json.dumps({"context": {"solver": "soft step, 8 substeps", "scene": "pyramid-N"}, "benchmarks": runs})


def pyramid_run(base, threads, ms, **extra):
    run = {"name": f"Pyramid/base:{base}/threads:{threads}/min_time:0.500/real_time",
           "run_name": f"Pyramid/base:{base}/threads:{threads}/min_time:0.500/real_time",
           "run_type": "iteration", "threads": 1, "real_time": ms, "time_unit": "ms",
           "bodies": base * (base + 1) / 2, "contact_pairs": 3.0 * base, "contact_points": 12.0 * base,
           "ms_per_step": ms, "solver_ns_per_point_pass": 90.0, "share_solve": 0.25, "share_relax": 0.5,
           "share_narrow_phase": 0.25}
    run.update(extra)
    return run


def test_contacts_benchmark_rows_speedups_and_shares(tmp_path):
    (tmp_path / "benchmarks").mkdir()
    (tmp_path / "benchmarks" / "contacts.json").write_text(contacts_json([
        pyramid_run(10, 1, 2.0), pyramid_run(10, 2, 1.6), pyramid_run(20, 1, 8.0)]))
    bench = benchmarks.contacts_benchmark(tmp_path)
    assert [(r["base"], r["threads"], r["bodies"]) for r in bench["rows"]] == [(10, 1, 55), (10, 2, 55), (20, 1, 210)]
    assert bench["rows"][1]["speedup"] == pytest.approx(1.25)
    assert bench["rows"][0]["speedup"] is None and bench["rows"][2]["speedup"] is None
    assert set(bench["stages"]) == {"solve", "relax", "narrow_phase"}
    assert bench["solver"] == "soft step, 8 substeps"


def triad_run(threads, at, gb_per_s):
    name = f"Triad/threads:{threads}/at:{at}/real_time"
    return {"name": name, "run_name": name, "run_type": "iteration", "iterations": 27, "real_time": 25.0,
            "time_unit": "ms", "bytes_per_second": gb_per_s * 1e9, "threads": threads}


def test_the_triad_beside_the_contact_step_is_its_start_and_end_bandwidth(tmp_path):
    # contacts_bench measures the machine's bandwidth first and last (at:0, at:1): the report shows
    # both, per thread count, so a slow spell shows beside the times
    (tmp_path / "benchmarks").mkdir()
    (tmp_path / "benchmarks" / "contacts.json").write_text(contacts_json([
        triad_run(1, 0, 13.6), triad_run(2, 0, 28.3), pyramid_run(10, 1, 2.0), triad_run(1, 1, 9.7),
        triad_run(2, 1, 20.4)]))
    bench = benchmarks.contacts_benchmark(tmp_path)
    assert bench["bandwidth"] == [dict(threads=1, start=pytest.approx(13.6), end=pytest.approx(9.7)),
                                  dict(threads=2, start=pytest.approx(28.3), end=pytest.approx(20.4))]
    # a Triad run is not read as a pyramid's
    assert [(r["base"], r["threads"]) for r in bench["rows"]] == [(10, 1)]
    broken = triad_run(1, 0, 13.6)
    del broken["bytes_per_second"]
    (tmp_path / "benchmarks" / "contacts.json").write_text(contacts_json([broken, pyramid_run(10, 1, 2.0)]))
    with pytest.raises(build_report.ReportError, match=r"contacts.json: benchmark 'Triad/threads:1/at:0.*bytes_per_second"):
        benchmarks.contacts_benchmark(tmp_path)


def test_thread_scaling_runs_are_the_paired_speedups(tmp_path):
    (tmp_path / "benchmarks").mkdir()
    scaling = {"name": "ThreadScaling/base:100/iterations:300/real_time",
               "run_name": "ThreadScaling/base:100/iterations:300/real_time", "run_type": "iteration",
               "iterations": 300, "real_time": 18.0, "time_unit": "ms",
               "ms_per_step_1t": 11.0, "ms_per_step_2t": 6.5, "speedup_2t": 11.0 / 6.5}
    failed = {"name": "ThreadScaling/base:50/iterations:600/real_time", "run_type": "iteration",
              "iterations": 0, "error_occurred": True, "error_message": "two threads did not give one thread's poses"}
    # in turns of ten steps: 30 iterations are 300 steps, its first steps of a turn read apart
    turns = {"name": "ThreadScaling/base:100/run:10/iterations:30/real_time", "run_type": "iteration",
             "iterations": 30, "real_time": 180.0, "time_unit": "ms",
             "ms_per_step_1t": 10.8, "ms_per_step_2t": 6.0, "speedup_2t": 1.8,
             "first_ms_1t": 12.0, "first_ms_2t": 7.0, "rest_ms_1t": 10.7, "rest_ms_2t": 5.9}
    ceiling = {"name": "Ceiling/at:1/iterations:10/real_time", "run_type": "iteration", "iterations": 10,
               "real_time": 80.0, "time_unit": "ms", "speedup_2t": 1.9}
    # the cores' round trip at the start, and the one the run in turns of ten met
    round_trip = {"name": "RoundTrip/at:0/iterations:5/real_time", "run_type": "iteration", "iterations": 5,
                  "real_time": 6.2, "time_unit": "ms", "round_trip_ns": 62.0}
    turns.update(round_trip_before_ns=62.0, round_trip_after_ns=318.0)
    (tmp_path / "benchmarks" / "contacts.json").write_text(
        contacts_json([pyramid_run(10, 1, 2.0), turns, scaling, failed, ceiling, round_trip]))
    bench = benchmarks.contacts_benchmark(tmp_path)
    # the machine's ceiling read beside them: at the end only here
    assert bench["ceiling"] == [None, pytest.approx(1.9)]
    assert bench["round_trip"] == [pytest.approx(62.0), None]
    assert [(p["base"], p["run"]) for p in bench["paired"]] == [(50, 1), (100, 1), (100, 10)]
    assert bench["paired"][0]["error"] == "two threads did not give one thread's poses"
    assert bench["paired"][1]["speedup"] == pytest.approx(11.0 / 6.5)
    assert bench["paired"][1]["steps"] == 300
    assert bench["paired"][1]["first"] is None
    assert bench["paired"][2]["steps"] == 300
    assert bench["paired"][2]["speedup"] == pytest.approx(1.8)
    assert bench["paired"][2]["first"] == (12.0, 7.0) and bench["paired"][2]["rest"] == (10.7, 5.9)
    # a run from before the round trip was taken says so; one with it carries its own
    assert bench["paired"][1]["round_trip"] is None
    assert bench["paired"][2]["round_trip"] == (pytest.approx(62.0), pytest.approx(318.0))
    broken = dict(round_trip, round_trip_ns="fast")
    (tmp_path / "benchmarks" / "contacts.json").write_text(contacts_json([pyramid_run(10, 1, 2.0), broken]))
    with pytest.raises(build_report.ReportError, match=r"contacts.json: benchmark 'RoundTrip/at:0.*fast"):
        benchmarks.contacts_benchmark(tmp_path)


def test_a_thread_scaling_median_counts_the_steps_of_one_repetition(tmp_path):
    # with --benchmark_repetitions the median's "iterations" is the number of repetitions
    (tmp_path / "benchmarks").mkdir()
    median = {"name": "ThreadScaling/base:100/run:10/iterations:30/real_time_median",
              "run_name": "ThreadScaling/base:100/run:10/iterations:30/real_time", "run_type": "aggregate",
              "aggregate_name": "median", "iterations": 3, "real_time": 180.0, "time_unit": "ms",
              "ms_per_step_1t": 8.3, "ms_per_step_2t": 5.0, "speedup_2t": 1.66,
              "first_ms_1t": 9.1, "first_ms_2t": 5.7, "rest_ms_1t": 8.2, "rest_ms_2t": 4.9}
    (tmp_path / "benchmarks" / "contacts.json").write_text(contacts_json([pyramid_run(10, 1, 2.0), median]))
    bench = benchmarks.contacts_benchmark(tmp_path)
    assert bench["paired"][0]["steps"] == 300
    # the separate runs' rows are still read beside them
    assert [(r["base"], r["threads"]) for r in bench["rows"]] == [(10, 1)]


def test_a_contacts_benchmark_without_its_counters_is_named(tmp_path):
    (tmp_path / "benchmarks").mkdir()
    broken = pyramid_run(10, 1, 2.0)
    del broken["ms_per_step"]
    (tmp_path / "benchmarks" / "contacts.json").write_text(contacts_json([broken]))
    with pytest.raises(build_report.ReportError, match=r"contacts.json: benchmark 'Pyramid/base:10.*ms_per_step"):
        benchmarks.contacts_benchmark(tmp_path)


def test_pyramid_series_draws_cost_against_bodies_with_the_benchmark(tmp_path):
    if not PHYSBENCH:
        pytest.skip("PHYSBENCH_EXE is not set (CTest sets it)")
    out = tmp_path / "r"
    subprocess.run([PHYSBENCH, "run", "-s", "pyramid-10,pyramid-20", "-e", "rtp,box2d", "--duration", "0.5",
                    "--budget", "0", "--out", str(out)], check=True, capture_output=True)
    table = pd.read_csv(out / "results.csv")
    ran = table[(table["status"] == "ok") & table["steps_per_s"].notna()]
    if ran.empty:
        pytest.skip("no engine in this build runs contact scenes")
    (out / "benchmarks").mkdir()
    (out / "benchmarks" / "contacts.json").write_text(contacts_json([
        triad_run(1, 0, 13.6), pyramid_run(10, 1, 2.0), pyramid_run(10, 2, 1.6), pyramid_run(20, 1, 8.0),
        pyramid_run(20, 2, 5.0), triad_run(1, 1, 9.7)]))
    page = readable(build_report.build_report(out).read_text())
    chart = page.split("Scaling: pyramid")[1].split("</section>")[0]
    assert "pyramid: ms per step against bodies" in chart
    # one line per engine/variant that ran both bases, each at 55 and 210 bodies
    for label, curve in ran.groupby(ran["engine"] + "/" + ran["variant"]):
        assert '"name":"' + label.replace("/", "\\u002f") + '"' in chart  # plotly escapes the slash
        assert sorted(curve["bodies"]) == [55, 210]
    assert "rtp soft-step, contacts_bench, 2 thread(s)" in chart
    assert "rtp contact step on the pyramids" in page and "<td>1.60</td>" not in page
    assert "<td>1.6</td><td>1.25×</td>" in page
    assert "at its start and its end: 13.6 and 9.7 GB/s on 1 thread." in page
    # drift against cost: both views for both pyramids, each with its front
    costs = page.split("Stacks: drift against cost")[1].split("</section>")[0]
    for name in ("pyramid-10", "pyramid-20"):
        assert f"<h3>{name}</h3>" in costs
    assert costs.count("Pareto front, each engine&#39;s defaults:") == 2
    assert costs.count("Pareto front, equal iterations (10):") == 2


def test_rain_verdicts_are_coloured_by_what_they_mean():
    rows = pd.DataFrame([
        dict(scenario="rain", label="rtp/soft-step", status="ok", contact_verdict="contained", penetration_max=0.01),
        dict(scenario="rain", label="bullet/float", status="ok", contact_verdict="escaped", penetration_max=0.2),
        dict(scenario="rain", label="ode/quickstep", status="ok", contact_verdict="unsettled", penetration_max=0.2),
        dict(scenario="rain", label="mujoco/euler", status="error", contact_verdict=None, penetration_max=None),
    ])
    table = contacts.verdict_table(rows)
    assert table["scenarios"] == ["rain"]
    cells = {r["label"]: r["cells"][0] for r in table["rows"]}
    assert cells == {"rtp/soft-step": ("contained", "stable"), "bullet/float": ("escaped", "unstable"),
                     "ode/quickstep": ("unsettled", "unstable"), "mujoco/euler": ("error", "unstable")}


def test_a_failed_reference_is_shown_on_its_rows_and_its_section(tmp_path):
    if not PHYSBENCH:
        pytest.skip("PHYSBENCH_EXE is not set (CTest sets it)")
    # the converged reference's interpreter is missing, so it fails
    scene = {"name": "capped", "dt": 1e-3, "duration": 1.0, "collisions": False, "gravity": [0, 0, 0],
             "bodies": [{"shape": {"type": "sphere", "radius": 0.1}, "mass": 1, "position": [1, 0, 0]}],
             "springs": [{"body_a": 0, "body_b": -1, "stiffness": 100}],
             "probe": {"metrics": ["position", "energy"]},
             "reference": {"kind": "converged", "dt_divisor": 1024}}
    (tmp_path / "capped.json").write_text(json.dumps(scene))
    out = tmp_path / "r"
    subprocess.run([PHYSBENCH, "run", "--scene", str(tmp_path / "capped.json"), "-e", "rtp", "--variant", "rk4",
                    "--budget", "0", "--out", str(out)], check=True, capture_output=True,
                   env={**os.environ, "PHYSBENCH_REFERENCE_PYTHON": str(tmp_path / "no-python")})
    (row,) = pd.read_csv(out / "results.csv").to_dict("records")
    assert row["reference_status"] == "error"
    assert table.reference_failed(row) == "error"
    page = readable(build_report.build_report(out).read_text())
    summary = page.split("<h2>All results</h2>")[1].split("</table>")[0]
    assert re.search(r'<td class="l ok">ok<br><span class="error">reference error</span></td>', summary)
    section = page.split("<h2>capped</h2>")[1]
    assert "the reference at dt 0.001 s did not run" in section
    assert "SciPy dop853" in section
    # a row whose reference ran carries no such note
    assert table.reference_failed({"reference_status": "ok"}) == ""
    assert table.reference_failed({"reference_status": float("nan")}) == ""


def sweep_row(variant, dt, status, error, steps_per_s=1e5):
    """A row of a swept scenario as results.csv has it: exploded rows carry no speed."""
    exploded = status == "exploded"
    return dict(scenario="spring", engine="rtp", variant=variant, label=f"rtp/{variant}", status=status, dt=dt,
                duration=1.0, steps_per_s=float("nan") if exploded else steps_per_s,
                wall_s_median=float("nan") if exploded else 1.0 / (dt * steps_per_s), position_err_max=error)


def test_speed_against_error_leaves_out_diverged_rows_as_it_does_exploded_ones(monkeypatch):
    rows = pd.DataFrame([
        sweep_row("rk4", 1 / 30, "ok", 1e-3), sweep_row("rk4", 1 / 60, "ok", 6e-5),
        sweep_row("rk4", 1 / 120, "ok", 4e-6),
        # midpoint at 1/30 s: finished, finite, its energy x1000: diverged, with a speed and an error
        sweep_row("midpoint", 1 / 30, "diverged", 30.0, steps_per_s=1e7), sweep_row("midpoint", 1 / 60, "ok", 1e-2),
        sweep_row("midpoint", 1 / 120, "ok", 2e-3),
        sweep_row("euler", 1 / 30, "exploded", 1e9), sweep_row("euler", 1 / 60, "ok", 0.2),
    ])
    monkeypatch.setattr(speed, "figure_html", lambda fig: fig)  # the figure, not its HTML
    fig, front = speed.speed_error(rows)
    curves = {trace.name.split(" (")[0]: list(trace.y) for trace in fig.data if trace.name != "Pareto front"}
    assert curves == {"rtp/rk4": [1e-3, 6e-5, 4e-6], "rtp/midpoint": [1e-2, 2e-3], "rtp/euler": [0.2]}
    # the diverged point is the cheapest of all: were it plotted, it would open the front
    assert all(p["error"] not in (build_report.fmt(30.0), build_report.fmt(1e9)) for p in front)
    assert {p["label"] for p in front} <= {"rtp/rk4", "rtp/midpoint", "rtp/euler"}


def test_run_summary_names_its_source_and_tables_each_engine(contact_results, tmp_path):
    out = tmp_path / "summary.md"
    subprocess.run([sys.executable, str(Path(build_report.__file__).parent / "run_summary.py"), str(contact_results),
                    "--title", "contacts", "-o", str(out)], check=True, capture_output=True)
    text = out.read_text()
    meta = json.loads((contact_results / "metadata.json").read_text())
    # the source: the command, the commit and the machine
    assert meta["command"] in text and meta["git_commit"] in text and meta["machine"]["cpu"] in text
    # the stack's best-knobs table has a row per engine; the bounce's verdict table a row per run
    stack = text.split("## tower-10")[1].split("##")[0]
    for engine in ("rtp", "box2d", "ode"):
        assert f"\n| {engine} |" in stack
    bounce = text.split("## bounce-e0.5")[1]
    assert "| rtp/soft-step | ok |" in bounce and "apex error max" in bounce


def test_run_summary_names_a_folder_that_is_not_a_run(tmp_path):
    result = subprocess.run([sys.executable, str(Path(build_report.__file__).parent / "run_summary.py"),
                             str(tmp_path / "nothing"), "--title", "x", "-o", str(tmp_path / "s.md")],
                            capture_output=True, text=True)
    assert result.returncode == 2 and "nothing" in result.stderr
    assert not (tmp_path / "s.md").exists()


def test_the_page_opens_with_the_answers_then_the_verdicts_and_the_stacks_replayed(contact_results):
    page = readable(build_report.build_report(contact_results).read_text())
    order = [page.index(marker) for marker in ('<section id="first">', '<section id="verdicts">',
                                                '<section id="stack-replays">', '<section id="glance">',
                                                '<section id="results">', '<section id="s-tower-10">')]
    assert order == sorted(order)
    first = page[order[0]:order[1]]
    assert "Which engine keeps a stack standing for the least time per step?" in first
    assert "ms per step, median" in first and "max drift (m)" in first
    # the tower's replay is up with the stacks, once; its section links to it
    replays = page[order[2]:order[3]]
    assert replays.count('class="replay" data-replay=') == 1 and '<a href="#s-tower-10">tower-10</a>' in replays
    tower = page[order[5]:].split("</section>")[0]
    assert "data-replay=" not in tower and 'href="#stack-replays"' in tower
    # every chart of the scenario has its question above it
    assert tower.count('<p class="question">') == tower.count('class="chart-spec"') > 0
    assert "How many joules does each engine add to the scene or take from it" in tower
    assert "Relative energy drift" not in tower
