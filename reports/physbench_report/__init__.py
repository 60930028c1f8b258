"""physbench's HTML report, built from a results folder (reports/build_report.py is its command).

    load         results.csv (checked against harness/results-schema.json), metadata.json,
                 trajectories (each read once), benchmarks/*.json
    style        hues, line styles, number format, anchors, a figure as a page fragment
    front        the first screen: each key question's chart, every engine's own Pareto front
    glance       the scoreboard, "At a glance"
    table        the full results table
    scenarios    one section per scenario: error over time (a contact scene's energy in J),
                 throughput, speed against error, each chart under its question
    speed        speed against error: measured orders, the Pareto front
    contacts     contact tables, the verdicts, stacks' drift against cost
    stability    stability maps of the swept families
    scaling      throughput or ms per step against a count
    benchmarks   the benchmark programs' JSON documents
    comparison   --compare OLD: what changed since an earlier run
    replay       the 3D replay viewer's data (poses/*.bin)
    settings     each adapter's non-default settings
    page         the page: every section through templates/page.html.j2

The report modules beside this package (compare.py for the comparison) are imported as top-level
modules: reports/ is on the path, as it is for build_report.py and history.py.
"""
