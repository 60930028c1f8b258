"""The contact views: each contact scenario's table, the verdicts of every engine on every contact
scenario, and the stacks' drift against cost at each engine's defaults and at equal iterations
(docs/metrics.md, "Contact reports")."""
from __future__ import annotations

import pandas as pd
import plotly.graph_objects as go
from plotly.subplots import make_subplots

from .rounds import BASELINE_SUFFIXES, NATIVE_SUFFIXES, format_ratio
from .speed import pareto_front
from .style import figure_html, fmt, hue

# the contact table of a contact scenario: results.csv column, heading (docs/metrics.md, "Contact")
CONTACT_COLUMNS = [
    ("contact_verdict", "verdict"), ("stack_drift_max", "drift max (m)"),
    ("drift_in_plane_max", "in the plane (m)"), ("drift_out_of_plane_max", "out of the plane (m)"),
    ("top_height_change", "top height change (m)"),
    ("penetration_max", "penetration max (m)"), ("penetration_final", "penetration final (m)"),
    ("energy_added_max", "energy added max (J)"), ("speed_max", "speed max (m/s)"),
    ("rest_speed_rms", "RMS speed, last second (m/s)"), ("apex_rel_err", "apex errors (relative)"),
    ("slide_distance", "slide (m)"), ("slide_accel", "slide a (m/s²)"), ("slide_accel_expected", "closed form a"),
    ("exchange_err", "exchange error"), ("roll_speed_rel_err", "rolling speed error (relative)"),
    ("roll_time_rel_err", "rolling time error (relative)"), ("cradle_answer", "cradle answer"),
    ("tunnelled", "tunnelled"), ("escaped", "escaped bodies"),
    ("contact_points", "contact points a step (the engine's count)"),
]
# verdicts that answer a contact scene's question badly (reports colour them)
FAILED_VERDICTS = {"collapsed", "sinks", "drifts", "settles", "tumbled", "no bounce", "tunnelled", "stuck",
                   "exploded", "slides, should stay", "stays, should slide", "escaped", "unsettled",
                   "gains height", "loses height", "slips", "rolls slow", "rolls fast", "gains energy",
                   "loses energy"}

# the two views of drift against cost (docs/engines.md, "Contacts"): each engine at its own
# defaults, and each at 10 velocity iterations or the nearest it has (Bullet's and Jolt's defaults
# are 10; rtp's soft step has no iteration count, so its 10-iteration solver stands for it there)
CONTACT_VIEWS = {
    "each engine's defaults": {"rtp": "soft-step", "bullet": "float", "ode": "quickstep", "box2d": "default",
                               "mujoco": "euler", "mujoco-2.2": "euler", "box2d-v3": "default",
                               "rapier": "default", "jolt": "default", "physx": "pgs", "box3d": "default"},
    "equal iterations (10)": {"rtp": "sequential-impulse", "bullet": "float", "ode": "quickstep-10",
                              "box2d": "iterations-10", "mujoco": "pgs-10", "mujoco-2.2": "pgs-10",
                              "box2d-v3": "iterations-10", "rapier": "iterations-10", "jolt": "default",
                              "physx": "iterations-10", "box3d": "iterations-10"},
}
# drift below this is drawn at it (a log axis has no zero)
DRIFT_FLOOR = 1e-6


def passed(rows: pd.DataFrame) -> pd.Series:
    """Which rows passed: status ok and, where the row has a contact verdict, not a failing one
    (collapsed, drifts, settles, sinks, …). Only these are named fastest or best, or drawn on a front."""
    verdicts = rows["contact_verdict"] if "contact_verdict" in rows else pd.Series("", index=rows.index)
    return (rows["status"] == "ok") & ~verdicts.isin(FAILED_VERDICTS)


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
                "stable" if text in ("stands", "stays", "slides", "stopped", "contained", "keeps height", "rolls",
                                     "elastic", "ok") else "")
            cells.append((text, css))
        rows.append(dict(label=label, cells=cells))
    return dict(scenarios=contact, rows=rows)


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


# a stack's verdicts from the worst to the best (docs/metrics.md, "Verdicts")
STACK_VERDICT_RANK = {"collapsed": 0, "sinks": 1, "drifts": 2, "settles": 3, "stands": 4}


def no_worse(mine: pd.Series, theirs: pd.Series) -> bool:
    """Whether one stack row is at least as accurate as another on every measure both have: a
    verdict no lower, and drift, the top's height change (either way) and the final penetration
    no larger. A measure missing from either row is not compared; an unknown verdict never is."""
    rank = STACK_VERDICT_RANK.get(mine.get("contact_verdict")), STACK_VERDICT_RANK.get(theirs.get("contact_verdict"))
    if rank[0] is None or rank[1] is None or rank[0] < rank[1]:
        return False
    for column, size in (("stack_drift_max", float), ("top_height_change", abs), ("penetration_final", float)):
        a, b = mine.get(column), theirs.get(column)
        if a is None or b is None or pd.isna(a) or pd.isna(b):
            continue
        if size(a) > size(b):
            return False
    return True


def best_configurations(results: pd.DataFrame, paired=None) -> list[dict]:
    """Per stack scenario, each engine read at its best knobs (issue 38's rule: no claim rests on an
    unequal setting): every row of the engine counts — each variant at its own settings and at
    every swept substep or iteration count. Per engine: its defaults' verdict and ms per step; the
    cheapest configuration whose verdict is `stands`, its ms and drift, and how many times rtp's
    cheapest standing configuration is faster (below 1: slower); and the least drift it reaches
    within the ms of rtp's default. Engines with no standing configuration say so. And the fair
    reading that holds where nothing stands too: against every configuration of a peer, rtp's
    cheapest configuration no less accurate (`no_worse`), the peer's time over rtp's; the
    least of those ratios is the peer's best showing (`matched`; `matched_baseline` against rtp at
    the baseline instruction set), and a peer configuration rtp matches with none is named. One
    thread each: rtp's two-thread variants are left out, as every peer runs on one. With `paired`
    (rounds.PairedRatios) the ratio is read round by round, with its 95 % interval."""
    defaults = CONTACT_VIEWS["each engine's defaults"]
    sections = []
    for name, rows in results.groupby("scenario", sort=False):
        if "stack_drift_max" not in rows or rows["stack_drift_max"].isna().all():
            continue
        rows = rows.copy()
        speed = rows["steps_per_s"] if "steps_per_s" in rows else pd.Series(float("nan"), index=rows.index)
        rows["ms"] = 1e3 / speed.where(speed > 0)
        # a build at another instruction set is read as an engine of its own: rtp at the baseline
        # (physbench-rtp-baseline), the equal-instruction-set comparison with the peers' generic
        # builds, and a peer built for this machine (rapier-native, box2d-v3-avx2), the native one
        # with rtp's own build
        other = ((rows["engine"] == "rtp") & rows["variant"].str.endswith(BASELINE_SUFFIXES)) | \
            ((rows["engine"] != "rtp") & rows["variant"].str.endswith(NATIVE_SUFFIXES))
        rows["who"] = rows["engine"].where(~other, rows["engine"] + rows["variant"].str.extract(
            "(" + "|".join(BASELINE_SUFFIXES + NATIVE_SUFFIXES) + ")$", expand=False).fillna(""))
        # one thread each: every peer runs on one, so rtp's two-thread variants take no part here
        ok = rows[(rows["status"] == "ok") & rows["ms"].notna() & ~rows["variant"].str.endswith("-2t")]
        stands = ok[ok.get("contact_verdict", pd.Series("", index=ok.index)) == "stands"]

        def cheapest(who: str):
            mine = stands[stands["who"] == who]
            return None if mine.empty else mine.loc[mine["ms"].idxmin()]

        def ratio_of(slower, faster_row):
            """slower's ms over faster_row's: the paired median and interval where both were timed
            in rounds, else one run's ratio (the interval's ends equal to it)"""
            interval = paired.ratio(name, float(slower["dt"]), slower["label"], faster_row["label"]) \
                if paired and slower["label"] != faster_row["label"] else None
            if interval is not None:
                return interval
            value = slower["ms"] / faster_row["ms"]
            return dict(median=value, lo=value, hi=value)

        def shown(r) -> str:
            return format_ratio(r) if r["lo"] != r["hi"] else fmt(r["median"])

        def faster(best, against):
            """best's ms over against's, paired by round where both were timed in rounds"""
            return "" if best is None or against is None else shown(ratio_of(best, against))

        def matched(who: str, against: str, default) -> str:
            """every ok configuration of `who` against `against`'s cheapest no less accurate one
            (the cheapest as the two are timed in the same rounds, not by one run's time): the
            least ratio (the peer's best showing), the ratio at the peer's defaults, and the
            configurations none matches"""
            theirs = ok[(ok["who"] == who) & ok["stack_drift_max"].notna()]
            mine = ok[(ok["who"] == against) & ok["stack_drift_max"].notna()]
            least, at_default, unmatched = None, None, []
            for index, q in theirs.iterrows():
                ratios = [(ratio_of(q, r), q["label"], r["label"]) for _, r in mine.iterrows() if no_worse(r, q)]
                if not ratios:
                    unmatched.append(q["label"])
                    continue
                r = max(ratios, key=lambda x: x[0]["median"])
                if least is None or r[0]["median"] < least[0]["median"]:
                    least = r
                if default is not None and index == default.name:
                    at_default = r

            def said(r):
                return f"{shown(r[0])}: {r[1]} against {r[2]}"
            parts = [said(least)] if least is not None else []
            if at_default is not None and at_default is not least:
                parts.append("at its defaults " + said(at_default))
            if unmatched:
                parts.append("none as accurate as " + ", ".join(unmatched))
            return "; ".join(parts)

        swept = rows.apply(lambda r: pd.notna(r.get("iterations")) or pd.notna(r.get("substeps")), axis=1)
        rtp_default = rows[(rows["engine"] == "rtp") & (rows["variant"] == defaults["rtp"]) & ~swept]
        rtp_ms = rtp_default["ms"].iloc[0] if not rtp_default.empty else float("nan")
        rtp_best = cheapest("rtp")
        rtp_base_whos = [w for w in rows["who"].unique() if w != "rtp" and w.startswith("rtp-")]
        rtp_base_best = cheapest(rtp_base_whos[0]) if rtp_base_whos else None
        table = []
        for who in rows["who"].unique():
            mine = rows[rows["who"] == who]
            engine = mine["engine"].iloc[0]
            wanted = defaults.get(engine) if who == engine else defaults.get(engine, "") + who[len(engine):]
            own = mine[(mine["variant"] == wanted) & ~swept[mine.index]]
            default = own.iloc[0] if not own.empty else None
            best = cheapest(who)
            within = ok[(ok["who"] == who) & (ok["ms"] <= rtp_ms) & ok["stack_drift_max"].notna()]
            least = within.loc[within["stack_drift_max"].idxmin()] if not within.empty else None
            table.append(dict(
                engine=who,
                default=("" if default is None else
                         f"{default['label']}: {default['status']}" if default["status"] != "ok" else
                         f"{default['label']}: {default.get('contact_verdict')}, {fmt(default['ms'])} ms, "
                         f"drift {fmt(default.get('stack_drift_max'))} m"),
                best=best["label"] if best is not None else "none stands",
                best_ms=fmt(best["ms"]) if best is not None else "",
                best_drift=fmt(best["stack_drift_max"]) if best is not None else "",
                ratio=faster(best, rtp_best),
                ratio_baseline=faster(best, rtp_base_best) if rtp_base_best is not None else "",
                matched="" if who.startswith("rtp") else matched(who, "rtp", default),
                matched_baseline=(matched(who, rtp_base_whos[0], default)
                                  if rtp_base_whos and not who.startswith("rtp") else ""),
                within=(f"{fmt(least['stack_drift_max'])} m ({least['label']})" if least is not None else "")))
        sections.append(dict(scenario=name, rows=table, rtp_ms=fmt(rtp_ms),
                             baseline=rtp_base_whos[0] if rtp_base_whos else None))
    return sections
