"""The whole page: each section's data from its module, rendered by templates/page.html.j2 (one
template a section, included in page order) into one self-contained index.html."""
from __future__ import annotations

from pathlib import Path

import jinja2

from . import replay
from .benchmarks import broadphase_benchmark, contacts_benchmark, narrowphase_benchmark, particle_benchmark
from .comparison import comparison_section
from .contacts import CONTACT_VIEWS, best_configurations, drift_cost_views, verdict_table
from .front import first_screen, scene_fronts_chart
from .glance import at_a_glance
from .rounds import PairedRatios, load_rounds, rtp_against_peers
from .load import is_nominal, load_results
from .profile import stage_profiles
from .scaling import scaling_charts
from .scenarios import scenario_sections
from .settings import engine_settings
from .stability import stability_maps
from .style import LAZY_CHARTS, anchor_of, learn_styles, plotly_js
from .table import results_table, table_script

# the page and its sections (templates/*.html.j2, report.css), escaped unless marked safe
TEMPLATES = jinja2.Environment(loader=jinja2.PackageLoader("physbench_report", "templates"), autoescape=True)


def build_report(folder: Path, compare_with: Path | None = None) -> Path:
    """index.html in the results folder (and, with compare_with, opening with what changed since
    that earlier run); a ReportError names what is wrong with either folder."""
    results, meta = load_results(folder)
    learn_styles(results)
    comparison = comparison_section(compare_with, folder)
    replays = replay.replays(folder, results, meta)
    for number, name in enumerate(replays, start=1):
        replays[name]["id"] = number  # its block's id on the page, wherever the page puts it
    # the stacks' replays follow their verdicts, near the top; the other scenes keep theirs
    stacks = [name for name in replays if "stack_drift_max" in results
              and results.loc[results["scenario"] == name, "stack_drift_max"].notna().any()]
    scenarios = scenario_sections(folder, results, meta, replays, replayed_above=set(stacks))
    glance = at_a_glance(results, meta)
    shown = {s["name"] for s in scenarios}
    for g in glance:
        g["linked"] = g["name"] in shown  # a family member is drawn in its family's map or chart
    benchmark = particle_benchmark(folder)
    contacts = contacts_benchmark(folder)
    broadphase, narrowphase = broadphase_benchmark(folder), narrowphase_benchmark(folder)
    nominal = results[[is_nominal(meta, r) for _, r in results.iterrows()]]
    paired = PairedRatios(load_rounds(folder))
    drift_cost = drift_cost_views(nominal)
    for d in drift_cost:  # above each stack's two views: every engine's own front over all it ran
        d["engine_fronts"] = scene_fronts_chart(results[results["scenario"] == d["scenario"]], meta)
    # in page order
    page = TEMPLATES.get_template("page.html.j2").render(
        meta=meta, plotlyjs=plotly_js(), lazycharts=LAZY_CHARTS, comparison=comparison,
        front=first_screen(results, meta, broadphase, narrowphase), glance=glance,
        table=results_table(results, meta), tablejs=table_script(), scenarios=scenarios,
        verdicts=verdict_table(nominal),
        stack_replays=[dict(name=n, anchor=anchor_of(n), replay=replays[n]) for n in stacks],
        drift_cost=drift_cost, contact_views=CONTACT_VIEWS,
        best_configurations=best_configurations(nominal, paired),
        rtp_against=rtp_against_peers(nominal, paired, CONTACT_VIEWS["each engine's defaults"]),
        contacts=contacts, profiles=stage_profiles(results, meta), families=stability_maps(results, meta),
        scaling=scaling_charts(results, meta, benchmark, contacts), benchmark=benchmark,
        narrowphase=narrowphase, broadphase=broadphase,
        engines=engine_settings(meta), viewerjs=replay.viewer_script(),
        has_replays=any(r["json"] for r in replays.values()))
    out = folder / "index.html"
    partial = folder / "index.html.partial"
    partial.write_text(page, encoding="utf-8")
    partial.replace(out)  # never a half-written report
    return out
