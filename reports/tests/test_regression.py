"""physbench run --shard, merge and compare: a sharded run merged is the unsharded run; compare flags an
injected slowdown and a worse result, and not a second run of the same build (docs/regression.md)."""
from __future__ import annotations

import csv
import json
import os
import re
import subprocess
from pathlib import Path

import pytest

from support import PHYSBENCH, figure_specs, physbench_run, readable

import compare
import merge

# what changes from run to run of one build: the timings
TIMING = {"repeats", "wall_s_median", "steps_per_s", "steps_per_s_min", "steps_per_s_max", "steps_per_s_repeats",
          "body_steps_per_s", "realtime_factor", "engine_version"}
SCENES = ["-s", "tumbling-box,projectile,spring-oscillator", "--no-sweep"]


def rows_of(folder: Path) -> list[dict]:
    with open(folder / "results.csv", newline="") as f:
        return list(csv.DictReader(f))


def physbench(*args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    if not PHYSBENCH:
        pytest.skip("PHYSBENCH_EXE is not set (CTest sets it)")
    return subprocess.run([PHYSBENCH, *args], capture_output=True, text=True, env=env)


def test_a_sharded_run_merged_is_the_unsharded_run(tmp_path):
    whole = physbench_run(tmp_path / "whole", *SCENES, "-e", "rtp")
    shards = [physbench_run(tmp_path / f"s{k}", *SCENES, "-e", "rtp", "--shard", f"{k}/3") for k in (1, 2, 3)]
    # a stride: every shard holds rows, and no row is in two
    counts = [len(rows_of(s)) for s in shards]
    assert all(counts) and sum(counts) == len(rows_of(whole))
    done = physbench("merge", "-o", str(tmp_path / "merged"), *map(str, reversed(shards)))
    assert done.returncode == 0, done.stderr
    merged = tmp_path / "merged"
    strip = lambda rows: [{k: v for k, v in r.items() if k not in TIMING} for r in rows]
    # the same rows, in the same order, with the same numbers (rtp is deterministic)
    assert strip(rows_of(merged)) == strip(rows_of(whole))
    for folder in ("trajectories", "poses", "scenes"):
        assert sorted(p.name for p in (merged / folder).iterdir()) == sorted(p.name for p in (whole / folder).iterdir())
    # the converged reference of tumbling-box ran in the shard that had its jobs, and says so
    meta, whole_meta = (json.loads((f / "metadata.json").read_text()) for f in (merged, whole))
    assert meta["scenarios"].keys() == whole_meta["scenarios"].keys()
    assert meta["scenarios"]["tumbling-box"]["reference_self_error"] == \
        whole_meta["scenarios"]["tumbling-box"]["reference_self_error"]
    assert meta["plan"]["fingerprint"] == whole_meta["plan"]["fingerprint"]
    assert len(meta["plan"]["merged_from"]) == 3


def test_merge_refuses_what_is_not_one_plans_shards(tmp_path):
    one = physbench_run(tmp_path / "one", *SCENES, "-e", "rtp", "--shard", "1/2")
    two = physbench_run(tmp_path / "two", *SCENES, "-e", "rtp", "--shard", "2/2")
    other = physbench_run(tmp_path / "other", "-s", "projectile", "--no-sweep", "-e", "rtp", "--shard", "2/2")
    cases = {
        "missing shard(s) 2/2": [one],
        "given twice": [one, one, two],
        "ran another plan": [one, other],
        "no such folder": [one, tmp_path / "absent"],
    }
    for why, folders in cases.items():
        out = tmp_path / f"out-{len(list(tmp_path.iterdir()))}"
        done = physbench("merge", "-o", str(out), *map(str, folders))
        assert done.returncode == 2 and why in done.stderr, (why, done.stderr)
        assert not (out / "results.csv").exists()
    # never into a folder that holds files
    busy = tmp_path / "busy"
    busy.mkdir()
    (busy / "keep.txt").write_text("an earlier run")
    done = physbench("merge", "-o", str(busy), str(one), str(two))
    assert done.returncode == 2 and "already holds files" in done.stderr
    assert not (busy / "results.csv").exists()


def test_shard_values_out_of_range_are_refused(tmp_path):
    for bad in ("0/2", "3/2", "2", "a/b", "1/0"):
        done = physbench("run", "-s", "projectile", "-e", "rtp", "--shard", bad, "-o", str(tmp_path / "x"))
        assert done.returncode == 2 and f"--shard {bad}" in done.stderr, done.stderr
        assert not (tmp_path / "x").exists()


def row(scenario="s", engine="rtp", variant="v", status="ok", speeds=(), **metrics) -> tuple:
    values = {"scenario": scenario, "engine": engine, "variant": variant, "dt": "0.01", "status": status,
              "message": "", **{k: str(v) for k, v in metrics.items()}}
    if speeds:
        values.update(steps_per_s=str(sorted(speeds)[len(speeds) // 2]), steps_per_s_min=str(min(speeds)),
                      steps_per_s_max=str(max(speeds)), steps_per_s_repeats=";".join(map(str, speeds)))
    return (scenario, engine, variant, 0.01), values


def table(*rows) -> dict:
    return dict(rows)


def test_compare_tells_each_kind_of_change():
    noise = [100, 104, 97, 101, 99, 103, 98, 102]
    peer = row(engine="bullet", variant="float", speeds=[50, 51, 49, 50, 52, 48, 50, 51])
    old = table(peer, row(speeds=noise, position_err_max=1e-3, stack_drift_max=0.002, contact_verdict="stands"),
                row(variant="broken", position_err_max=1e-3), row(variant="same", speeds=noise, position_err_max=2e-3))
    new = table(peer, row(speeds=[x * 0.7 for x in noise], position_err_max=3e-3, stack_drift_max=0.5,
                          contact_verdict="collapsed"),
                row(variant="broken", status="exploded", position_err_max=1e-3),
                row(variant="same", speeds=[x + 1 for x in reversed(noise)], position_err_max=2e-3 * (1 + 1e-9)))
    result = compare.compare(old, new, against="bullet")
    assert result.against == "bullet"
    verdicts = {(c.key[2], c.verdict) for c in result.changes}
    assert verdicts == {("v", "slower"), ("v", "less accurate"), ("v", "worse verdict"), ("broken", "broken")}
    assert len(result.regressions) == 4
    # the other way round is all better, and no regression
    back = compare.compare(new, old, against="bullet")
    assert {c.verdict for c in back.changes} == {"faster", "more accurate", "better verdict", "fixed"}
    assert not back.regressions
    # a change within the repeats' spread is not a change, however the threshold is set
    within = table(peer, row(speeds=[x * 0.97 for x in noise]))
    assert not compare.compare(table(peer, row(speeds=noise)), within, speed_threshold=0.0).changes
    # the peers' own change is set aside: every engine 40 % slower is no change of rtp's
    slow = lambda r: (r[0], {**r[1], **row(r[0][0], r[0][1], r[0][2], speeds=[
        float(x) * 0.6 for x in r[1]["steps_per_s_repeats"].split(";")])[1]})
    everything_slower = table(slow(peer), slow(row(speeds=noise)))
    assert not compare.compare(table(peer, row(speeds=noise)), everything_slower, against="bullet").changes


def test_a_row_is_one_scene_step_engine_variant_and_swept_knob(tmp_path):
    """compare and history tell a sweep's rows apart by iterations and substeps; a run from before
    those columns matches the rows at each variant's own settings."""
    def write(folder: Path, rows: list[dict]) -> Path:
        folder.mkdir()
        columns = ["scenario", "engine", "variant", "dt", "iterations", "substeps", "status", "message",
                   "stack_drift_max"]
        with open(folder / "results.csv", "w", newline="") as f:
            writer = csv.DictWriter(f, columns, extrasaction="ignore")
            writer.writeheader()
            writer.writerows(rows)
        return folder
    base = {"scenario": "tower-10", "engine": "rtp", "variant": "sequential-impulse", "dt": "0.016666666666666666",
            "status": "ok", "message": ""}
    swept = [{**base, "stack_drift_max": "0.05"}, {**base, "iterations": "1", "stack_drift_max": "0.7"},
             {**base, "iterations": "16", "stack_drift_max": "0.02"}, {**base, "substeps": "2", "status": "unsupported"}]
    new = compare.read_rows(write(tmp_path / "new", swept))
    assert len(new) == 4, "a sweep's rows are rows of their own, not one row overwritten"
    # the same run with one iteration's drift doubled: only that row is less accurate
    worse = compare.read_rows(write(tmp_path / "worse", [swept[0], {**swept[1], "stack_drift_max": "1.4"}, *swept[2:]]))
    changes = compare.compare(new, worse).changes
    assert [(c.key[4], c.verdict) for c in changes] == [("1", "less accurate")]
    assert "rtp/sequential-impulse iterations 1" in compare.format_text(compare.compare(new, worse), tmp_path, tmp_path)
    # a run from before the columns: its row is the variant's own
    old = tmp_path / "old"
    old.mkdir()
    (old / "results.csv").write_text("scenario,engine,variant,dt,status,message,stack_drift_max\n"
                                     "tower-10,rtp,sequential-impulse,0.016666666666666666,ok,,0.05\n")
    result = compare.compare(compare.read_rows(old), new)
    assert result.matched == 1 and len(result.only_new) == 3 and not result.changes


def synthetic_run(seed: int, slowdown: dict[str, float] | None = None, spell: float = 1.0) -> dict:
    """compare's input without timing anything: six engines on three scene steps, each row's seven
    repeats drawn as a machine gives them — the engine's speed, each repeat slowed by a half-normal
    share of its time (σ 8 %: a repeat is disturbed, never sped up) — the whole run slowed by `spell`
    (a slower machine) and the engines named in `slowdown` by their share more time a step."""
    import numpy as np

    rng = np.random.default_rng(seed)
    speeds = {"rtp": 1000.0, "bullet": 700.0, "jolt": 1500.0, "physx": 2000.0, "box3d": 900.0, "ode": 400.0}
    rows = {}
    for scenario in ("tower-20", "pyramid-20", "pyramid-50"):
        for engine, speed in speeds.items():
            mean = speed / spell / (1.0 + (slowdown or {}).get(engine, 0.0))
            repeats = mean / (1.0 + 0.08 * np.abs(rng.standard_normal(7)))
            row = dict(scenario=scenario, engine=engine, variant="default", dt="0.0166666667", iterations="",
                       substeps="", status="ok", steps_per_s_max=str(repeats.max()),
                       steps_per_s_min=str(repeats.min()), steps_per_s_repeats=";".join(f"{v:.4g}" for v in repeats))
            rows[compare.row_key(row)] = row
    return rows


def test_compare_flags_a_15_percent_slowdown_and_nothing_between_runs_of_one_build():
    # machine-independent: the rows are drawn, not timed (the end-to-end check on real runs is
    # scripts/check-compare.sh, a benchmark, run by hand or nightly: docs/regression.md)
    # ten draws each way: the same build on a slower or faster machine is never flagged; one engine
    # 15 % slower a step (13 % less speed) is flagged on at least two of its three rows every time
    # (seven repeats a row at this spread give the rank test p < 0.01 on most rows, not on all),
    # and nothing else is
    old = synthetic_run(seed=1)
    bullet = {(s, "bullet") for s in ("tower-20", "pyramid-20", "pyramid-50")}
    for seed in range(2, 12):
        same = compare.compare(old, synthetic_run(seed, spell=(0.8, 1.0, 1.7)[seed % 3]))
        assert not same.changes, compare.format_text(same, Path("old"), Path("same"))
        slowed = compare.compare(old, synthetic_run(seed + 100, slowdown={"bullet": 0.15}, spell=1.3))
        flagged = {(c.key[0], c.key[1]) for c in slowed.changes}
        text = compare.format_text(slowed, Path("old"), Path("slowed"))
        assert flagged <= bullet and len(flagged) >= 2, text
        assert all(c.verdict == "slower" for c in slowed.changes), text


def test_compare_says_what_is_wrong_with_its_input(tmp_path):
    done = physbench("compare", str(tmp_path), str(tmp_path))
    assert done.returncode == 2 and "no results.csv" in done.stderr
    good = physbench_run(tmp_path / "good", "-s", "projectile", "--no-sweep", "-e", "rtp")
    done = physbench("compare", str(good), str(good), "--against", "nosuch")
    assert done.returncode == 2 and "--against nosuch" in done.stderr


def test_the_history_keeps_runs_small_compares_each_with_the_last_and_draws_trends(tmp_path):
    import history

    first = physbench_run(tmp_path / "first", *SCENES, "-e", "rtp")
    second = physbench_run(tmp_path / "second", *SCENES, "-e", "rtp")
    store = tmp_path / "history"
    entry, code = history.add(first, store)
    assert code == 0 and "nothing to compare" in (entry / "compare.txt").read_text()
    entry2, code = history.add(second, store)
    # deterministic rows, no timing (--budget 0): nothing changed, and compare.txt says so
    assert code == 0 and "no regression" in (entry2 / "compare.txt").read_text()
    assert history.entries(store) == sorted([entry, entry2])
    # an entry holds the rows and the metadata only, compressed: a small fraction of the run's folder
    run_bytes = sum(p.stat().st_size for p in first.rglob("*") if p.is_file())
    entry_bytes = sum(p.stat().st_size for p in entry.iterdir())
    assert entry_bytes < 0.05 * run_bytes, (entry_bytes, run_bytes)
    assert history.read_entry_rows(entry).keys() == {
        (r["scenario"], r["engine"], r["variant"], float(r["dt"]), r["iterations"], r["substeps"])
        for r in rows_of(first)}
    with pytest.raises(history.HistoryError, match="in the history already"):
        history.add(first, store)
    assert history.report(store, store / "index.html") == 2
    page = (store / "index.html").read_text()
    for scenario in ("tumbling-box", "projectile", "spring-oscillator"):
        assert f"id='s-{scenario}'" in page
    assert page.count("Plotly.newPlot") >= 3  # a chart of each scenario's main error at least


def test_the_report_opens_with_what_changed_since_an_earlier_run(tmp_path):
    import shutil

    import build_report

    old = physbench_run(tmp_path / "old", "-s", "projectile,tumbling-box", "--no-sweep", "-e", "rtp")
    new = tmp_path / "new"
    shutil.copytree(old, new)
    # the new run's rk4 tumbles three times as far from the reference
    rows = rows_of(new)
    for r in rows:
        if r["scenario"] == "tumbling-box" and r["variant"] == "rk4":
            r["orientation_err_max"] = str(3 * float(r["orientation_err_max"]))
    with open(new / "results.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()), lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    page = readable(build_report.build_report(new, old).read_text())
    section = page[page.index("<section id=\"compare\">"):page.index('<section id="results">')]
    assert "1 regression(s)" in section
    assert "less accurate" in section and "tumbling-box" in section and "rtp/rk4" in section
    # without --compare there is no such section, and the same run against itself has no change
    assert "id=\"compare\"" not in readable(build_report.build_report(new).read_text())
    same = readable(build_report.build_report(old, old).read_text())
    assert "no regression" in same and "No change beyond the noise." in same


def test_the_report_holds_results_to_the_schema_physbench_writes_by(tmp_path):
    import json as json_module
    import shutil

    import build_report

    good = physbench_run(tmp_path / "good", "-s", "projectile,tower-10", "--no-sweep", "-e", "rtp")
    schema = json_module.loads(build_report.SCHEMA_FILE.read_text())
    # the runner writes exactly the schema's columns, in its order
    with open(good / "results.csv", newline="") as f:
        assert next(csv.reader(f)) == [c["name"] for c in schema["columns"]]
    build_report.build_report(good)

    def broken(name: str, change) -> Path:
        folder = tmp_path / name
        shutil.copytree(good, folder)
        (folder / "index.html").unlink()  # the good run's report
        rows = rows_of(folder)
        fields = list(rows[0].keys())
        fields = change(rows, fields) or fields
        with open(folder / "results.csv", "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
            writer.writeheader()
            writer.writerows(rows)
        return folder

    def rename(rows, fields):
        for r in rows:
            r["stack_drift_mx"] = r.pop("stack_drift_max")
        return [f if f != "stack_drift_max" else "stack_drift_mx" for f in fields]

    cases = {
        "columns not in results-schema.json: \\['stack_drift_mx'\\]": broken("renamed", rename),
        "row 3: dt = 'fast' is not a number": broken("word", lambda rows, _: rows[1].update(dt="fast")),
        "row 2: status 'fine' is not one of": broken("status", lambda rows, _: rows[0].update(status="fine")),
        "row 2: engine is empty": broken("empty", lambda rows, _: rows[0].update(engine="")),
    }
    for why, folder in cases.items():
        with pytest.raises(build_report.ReportError, match=why):
            build_report.build_report(folder)
        assert not (folder / "index.html").exists()


def test_the_front_page_names_the_fastest_the_most_accurate_and_the_failures(tmp_path):
    import build_report

    run = physbench_run(tmp_path / "run", "-s", "tumbling-box,projectile", "-e", "rtp,test-fault",
                        "--variant", "rk4,euler,midpoint,abort", "--timeout", "20")
    # --budget 0 times one pass: enough to rank, and the page must rank as the file says
    page = readable(build_report.build_report(run).read_text())
    glance = page[page.index('<section id="glance">'):page.index('<section id="results">')]
    rows = [r for r in rows_of(run) if r["scenario"] == "tumbling-box" and r["status"] == "ok"
            and abs(float(r["dt"]) - 1 / 60) < 1e-9]
    fastest = max(rows, key=lambda r: float(r["steps_per_s"]))
    accurate = min(rows, key=lambda r: float(r["orientation_err_max"]))
    line = glance[glance.index('<tr><td class="l"><a href="#s-tumbling-box"'):].split("</tr>")[0]
    assert f"{fastest['engine']}/{fastest['variant']} (" in line.split("</td>")[1]
    assert accurate["variant"] == "rk4" and "rtp/rk4 (" in line.split("</td>")[2]
    # the engine that aborts is a failure in words, with its reason
    assert "test-fault/abort crashed at dt = " in line
    # every scenario links to its section
    assert 'id="s-tumbling-box"' in page and 'id="s-projectile"' in page


def plotted_traces(page: str) -> list[dict]:
    """Every trace of every chart in the page, as plotly is given it (the history's page draws
    with plotly's own scripts, the report's from each chart's JSON)."""
    decoder = json.JSONDecoder()
    traces = [t for spec in figure_specs(page) for t in spec["data"]]
    for call in re.finditer(r'Plotly\.newPlot\(\s*"', page):  # plotly's own: the div's id, then the data
        data, _ = decoder.raw_decode(page, page.index("[", page.index(",", call.start())))
        traces.extend(data)
    return traces


def test_each_engine_has_one_hue_and_each_variant_one_line_style_on_every_chart(tmp_path):
    import build_report

    run = physbench_run(tmp_path / "run", "-s", "tumbling-box,projectile", "-e", "rtp,ode",
                        "--variant", "rk4,euler,midpoint,quickstep,step")
    traces = [t for t in plotted_traces(build_report.build_report(run).read_text()) if t.get("type") == "scatter"]
    styles: dict[str, set] = {}
    for t in traces:
        name = t.get("name", "").split(" (order")[0]
        if "/" in name:
            styles.setdefault(name, set()).add((t["line"]["color"], t["line"].get("dash")))
    # rk4, euler and midpoint of rtp, quickstep and step of ODE, each on several charts
    assert {"rtp/rk4", "rtp/euler", "ode/quickstep", "ode/step"} <= styles.keys(), styles.keys()
    for label, seen in styles.items():
        assert len(seen) == 1, (label, seen)  # the same on every chart
    hues = {label.split("/")[0]: next(iter(seen))[0] for label, seen in styles.items()}
    assert styles["rtp/rk4"] != styles["rtp/euler"]                      # variants differ by dash
    assert next(iter(styles["rtp/rk4"]))[0] == next(iter(styles["rtp/euler"]))[0]  # one engine, one hue
    assert hues["rtp"] != hues["ode"]
    bars = [t for t in plotted_traces(build_report.build_report(run).read_text()) if t.get("type") == "bar"]
    assert bars and all(len(set(b["marker"]["color"])) == 2 for b in bars if len(set(b["x"])) > 3)


def test_the_documented_history_query_reads_rtps_ratio_to_bullet_over_the_runs(tmp_path):
    import duckdb
    import history

    docs = (Path(__file__).resolve().parents[2] / "docs" / "regression.md").read_text()
    query = docs.split("### Querying the history", 1)[1].split("```sql\n", 1)[1].split("\n```", 1)[0]
    store = tmp_path / "history"
    header = "scenario,engine,variant,dt,iterations,substeps,status,steps_per_s\n"
    for night, (rtp, bullet) in enumerate([(1000.0, 400.0), (1100.0, 400.0), (900.0, 450.0)]):
        run = tmp_path / f"run{night}"
        run.mkdir()
        (run / "results.csv").write_text(
            header + f"pyramid-20,rtp,soft-step,0.0166666667,,,ok,{rtp}\n"
            f"pyramid-20,bullet,float,0.0166666667,,,ok,{bullet}\n"
            f"pyramid-20,bullet,float,0.0166666667,,4,ok,{bullet / 4}\n"  # a swept row: not the default
            f"tower-20,rtp,soft-step,0.0166666667,,,ok,9999\n")
        (run / "metadata.json").write_text(json.dumps({"created": f"2026-12-0{night + 1}T00:00:00Z",
                                                       "git_commit": f"c{night}"}))
        history.add(run, store)
    rows = duckdb.sql(query.replace("'history/", f"'{store}/")).fetchall()
    assert [(commit, round(ratio, 6)) for _, commit, ratio in rows] == [("c2", 2.0), ("c1", 2.75), ("c0", 2.5)]
