"""Speed ratios paired by timing round (reports/physbench_report/rounds.py)."""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from physbench_report.rounds import PairedRatios, bootstrap_median, format_ratio, load_rounds  # noqa: E402

HEADER = "scenario,dt,engine,variant,iterations,substeps,round,order,repeats,seconds_per_step\n"


def write_rounds(folder: Path, lines: list[str]) -> None:
    (folder / "timing_rounds.csv").write_text(HEADER + "".join(line + "\n" for line in lines))


def test_a_ratio_is_read_round_by_round(tmp_path):
    # the machine doubles its speed halfway through: each engine's own times spread 2x, but within
    # each round the peer takes exactly 3x rtp's time, so the paired ratio has no spread at all
    lines = []
    for k, scale in enumerate([1.0, 1.0, 2.0, 2.0, 1.5], start=1):
        lines.append(f"tower-20,0.0166666667,rtp,soft-step,,,{k},1,3,{1e-4 * scale}")
        lines.append(f"tower-20,0.0166666667,bullet,float,,,{k},2,3,{3e-4 * scale}")
        lines.append(f"tower-20,0.0166666667,bullet,float,,4,{k},3,3,{9e-4 * scale}")
    write_rounds(tmp_path, lines)
    paired = PairedRatios(load_rounds(tmp_path))
    r = paired.ratio("tower-20", 1 / 60, "bullet/float", "rtp/soft-step")
    assert r["rounds"] == 5
    assert abs(r["median"] - 3.0) < 1e-9 and abs(r["lo"] - 3.0) < 1e-9 and abs(r["hi"] - 3.0) < 1e-9
    # a swept configuration is its own label, as in results.csv
    r = paired.ratio("tower-20", 1 / 60, "bullet/float substeps=4", "rtp/soft-step")
    assert abs(r["median"] - 9.0) < 1e-9
    assert format_ratio(r) == "9× (9–9)"


def test_a_pair_timed_in_fewer_than_three_common_rounds_has_no_ratio(tmp_path):
    write_rounds(tmp_path, ["s,0.01,rtp,rk4,,,1,1,3,1e-6", "s,0.01,rtp,rk4,,,2,1,1,1e-6",
                            "s,0.01,ode,step,,,1,2,3,2e-6", "s,0.01,ode,step,,,2,2,1,2e-6"])
    paired = PairedRatios(load_rounds(tmp_path))
    assert paired.ratio("s", 0.01, "ode/step", "rtp/rk4") is None
    assert paired.ratio("s", 0.02, "ode/step", "rtp/rk4") is None  # another step
    assert format_ratio(None) == ""


def test_a_folder_from_before_rounds_has_no_ratios(tmp_path):
    assert PairedRatios(load_rounds(tmp_path)).ratio("s", 0.01, "a/b", "c/d") is None


def test_the_bootstrap_interval_holds_the_median_and_widens_with_spread():
    rng = np.random.default_rng(1)
    narrow = 2.0 + 0.01 * rng.standard_normal(9)
    wide = 2.0 + 0.3 * rng.standard_normal(9)
    m, lo, hi = bootstrap_median(narrow)
    assert lo <= m <= hi and hi - lo < 0.05
    m2, lo2, hi2 = bootstrap_median(wide)
    assert lo2 <= m2 <= hi2 and hi2 - lo2 > 5 * (hi - lo)
    # the same interval every time (a fixed seed)
    assert bootstrap_median(wide) == (m2, lo2, hi2)


def test_the_glance_lists_a_scenario_where_every_run_failed():
    # a scenario with no run that passed (every stack collapsed) once broke the front page: an
    # empty row mask selected no columns
    import pandas as pd
    from physbench_report.glance import at_a_glance

    rows = pd.DataFrame([
        dict(scenario="tower-20", engine="bullet", variant="float", label="bullet/float", dt=1 / 60, status="ok",
             contact_verdict="collapsed", steps_per_s=1000.0, message="collapsed (toppled)"),
        dict(scenario="tower-20", engine="jolt", variant="default", label="jolt/default", dt=1 / 60, status="crashed",
             contact_verdict=None, steps_per_s=None, message="killed by signal 11"),
    ])
    (entry,) = at_a_glance(rows, {"scenarios": {"tower-20": {"dt": 1 / 60}}})
    assert entry["fastest"] == ""
    assert len(entry["failures"]) == 2, entry["failures"]


def test_each_peer_is_given_against_rtp_at_both_instruction_sets(tmp_path):
    # rtp's native build takes 1, its baseline build 4 and Bullet 2 (x 1e-4 s) in every round, the
    # machine's speed changing from round to round: Bullet is 2x the native build and 0.5x the
    # baseline one; a run without the baseline build says "not run"
    import pandas as pd
    from physbench_report.rounds import rtp_against_peers

    lines = []
    for k, scale in enumerate([1.0, 1.3, 0.8], start=1):
        lines.append(f"tower-20,0.0166666667,rtp,soft-step,,,{k},1,3,{1e-4 * scale}")
        lines.append(f"tower-20,0.0166666667,rtp,soft-step-x86-64,,,{k},2,3,{4e-4 * scale}")
        lines.append(f"tower-20,0.0166666667,bullet,float,,,{k},3,3,{2e-4 * scale}")
    write_rounds(tmp_path, lines)
    paired = PairedRatios(load_rounds(tmp_path))
    rows = pd.DataFrame([
        dict(scenario="tower-20", engine=e, variant=v, label=f"{e}/{v}", dt=1 / 60, status="ok",
             contact_verdict="stands", iterations=float("nan"), substeps=float("nan"))
        for e, v in [("rtp", "soft-step"), ("rtp", "soft-step-x86-64"), ("bullet", "float")]])
    defaults = {"rtp": "soft-step", "bullet": "float"}
    (scene,) = rtp_against_peers(rows, paired, defaults)
    (bullet,) = scene["peers"]
    assert scene["rtp_baseline"] == "rtp/soft-step-x86-64"
    assert bullet["ratio"] == "2× (2–2)"
    assert bullet["ratio_baseline"] == "0.5× (0.5–0.5)"
    (scene,) = rtp_against_peers(rows[rows["variant"] != "soft-step-x86-64"], paired, defaults)
    assert scene["rtp_baseline"] is None and scene["peers"][0]["ratio_baseline"] == "not run"
