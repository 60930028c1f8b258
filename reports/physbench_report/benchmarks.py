"""The benchmark programs' documents that bench.sh writes into benchmarks/ (Google Benchmark JSON):
particles_bench, broadphase_bench, narrowphase_bench and contacts_bench, each as its section's
rows and charts, or None when the file is absent."""
from __future__ import annotations

import statistics
from pathlib import Path

import plotly.graph_objects as go

from .load import ReportError, benchmark_document
from .style import figure_html, hue


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


def contacts_benchmark(folder: Path) -> dict | None:
    """rtp's contact step on the pyramids (bench/contacts_bench.cpp), if bench.sh wrote it: per
    (base, threads) the ms per step, the bodies, contact pairs and points, the solver's ns per
    point and pass, and each stage's share of the step; the median of repetitions when there are
    any. A run without the counters is named as malformed."""
    document = benchmark_document(folder, "contacts.json")
    if document is None:
        return None
    cases: dict[tuple, dict] = {}
    paired: dict[tuple, dict] = {}  # (base, steps a turn) -> its ThreadScaling row
    # the machine's own figures in the same run, each at the run's start (at:0) and end (at:1):
    # its memory bandwidth (bench/triad.h, GB/s, per thread count), its two-thread ceiling and
    # the cores' round trip (bench/ceiling.h, a speedup and ns); each run's, by (threads,) at
    machine = {"Triad/": (("threads", "at"), "bytes_per_second", 1e-9),
               "Ceiling/": (("at",), "speedup_2t", 1.0),
               "RoundTrip/": (("at",), "round_trip_ns", 1.0)}
    readings: dict[str, dict[tuple, list]] = {prefix: {} for prefix in machine}
    for run in document.get("benchmarks", []):
        name = run.get("run_name", run.get("name", ""))
        prefix = next((p for p in machine if name.startswith(p)), None)
        if prefix is not None:
            if run.get("run_type") == "aggregate" or run.get("error_occurred"):
                continue
            keys, counter, scale = machine[prefix]
            fields = dict(part.split(":", 1) for part in name.split("/")[1:] if ":" in part)
            try:
                key = tuple(int(fields[k]) for k in keys)
                readings[prefix].setdefault(key, []).append(float(run[counter]) * scale)
            except (KeyError, ValueError) as exc:
                raise ReportError(f"{folder / 'benchmarks' / 'contacts.json'}: benchmark {name!r} lacks "
                                  f"or garbles {exc}") from exc
            continue
        if name.startswith("ThreadScaling/"):
            scaling = thread_scaling_row(folder, name, run)
            if scaling is not None:
                paired[(scaling["base"], scaling["run"])] = scaling
            continue
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
    if not cases and not paired:
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
    triad = readings["Triad/"]

    def start_and_end(prefix: str) -> list | None:
        """a figure's median at the run's start and end (None where not run), None if never run"""
        runs = readings[prefix]
        return [statistics.median(runs[(at,)]) if (at,) in runs else None for at in (0, 1)] if runs else None

    bandwidth = [dict(threads=threads, start=statistics.median(triad[(threads, 0)]) if (threads, 0) in triad else None,
                      end=statistics.median(triad[(threads, 1)]) if (threads, 1) in triad else None)
                 for threads in sorted({threads for threads, _ in triad})]
    return dict(rows=rows, stages=stages, chart=figure_html(fig) if rows else "", solver=context.get("solver", ""),
                scene=context.get("scene", ""), paired=[paired[key] for key in sorted(paired)],
                bandwidth=bandwidth,
                ceiling=start_and_end("Ceiling/"), round_trip=start_and_end("RoundTrip/"))


def thread_scaling_row(folder: Path, name: str, run: dict) -> dict | None:
    """One ThreadScaling run of contacts_bench (one thread against two, the same steps in turn,
    `run` steps a turn: 1 where the name has no run, as before it had one): its base and run,
    each world's ms per step and the speedup, and for turns of several steps each world's first
    step of a turn apart from the rest, and the cores' round trip before its turns and after them
    (ns; None in a run from before it was taken); None for an aggregate other than the median, a failed run named as
    such."""
    if run.get("run_type") == "aggregate" and run.get("aggregate_name") != "median":
        return None
    fields = dict(part.split(":", 1) for part in name.split("/")[1:] if ":" in part)
    if run.get("error_occurred"):
        return dict(base=int(fields.get("base", 0)), run=int(fields.get("run", 1)),
                    error=run.get("error_message", "failed"))
    try:
        turn = int(fields.get("run", 1))
        first = (float(run["first_ms_1t"]), float(run["first_ms_2t"])) if turn > 1 else None
        rest = (float(run["rest_ms_1t"]), float(run["rest_ms_2t"])) if turn > 1 else None
        return dict(base=int(fields["base"]), run=turn, ms_1t=float(run["ms_per_step_1t"]),
                    ms_2t=float(run["ms_per_step_2t"]), speedup=float(run["speedup_2t"]),
                    # (a median's own "iterations" counts the repetitions: the name holds the run's)
                    steps=int(fields.get("iterations", run["iterations"])) * turn, first=first, rest=rest,
                    round_trip=(float(run["round_trip_before_ns"]), float(run["round_trip_after_ns"]))
                    if "round_trip_before_ns" in run else None,
                    error=None)
    except (KeyError, ValueError) as exc:
        raise ReportError(f"{folder / 'benchmarks' / 'contacts.json'}: benchmark {name!r} lacks "
                          f"or garbles {exc}") from exc
