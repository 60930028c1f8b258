"""Speed ratios paired by timing round (docs/metrics.md, "Interleaved timing"): a scene step's jobs
are timed in rounds, each job once a round in a fresh order, so within a round every engine met the
same state of the machine. The ratio of two configurations is read round by round; its median and
a bootstrap 95 % interval over the rounds are what the report shows beside it."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .load import knob_suffix

BOOTSTRAP_RESAMPLES = 2000
BOOTSTRAP_SEED = 0  # the same interval on every build of the same folder


def load_rounds(folder: Path) -> pd.DataFrame:
    """timing_rounds.csv with a label column as results.csv's (engine/variant and knobs); an empty
    frame for a folder from before rounds (or one merged from such)."""
    csv = folder / "timing_rounds.csv"
    if not csv.is_file():
        return pd.DataFrame(columns=["scenario", "dt", "label", "round", "seconds_per_step"])
    rounds = pd.read_csv(csv)
    rounds["label"] = rounds["engine"] + "/" + rounds["variant"] + [knob_suffix(r) for _, r in rounds.iterrows()]
    return rounds


def bootstrap_median(ratios: np.ndarray) -> tuple[float, float, float]:
    """The median of the per-round ratios and the 2.5th and 97.5th percentiles of the medians of
    BOOTSTRAP_RESAMPLES resamples of the rounds, drawn with replacement."""
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    draws = rng.choice(ratios, size=(BOOTSTRAP_RESAMPLES, len(ratios)), replace=True)
    medians = np.median(draws, axis=1)
    return float(np.median(ratios)), float(np.percentile(medians, 2.5)), float(np.percentile(medians, 97.5))


class PairedRatios:
    """The time of one configuration over another's at a scene step, round by round."""

    def __init__(self, rounds: pd.DataFrame):
        self.by_step = {key: group.set_index(["label", "round"])["seconds_per_step"]
                        for key, group in rounds.groupby(["scenario", "dt"])} if not rounds.empty else {}

    def ratio(self, scenario: str, dt: float, slower: str, faster: str) -> dict | None:
        """slower's seconds per step over faster's, paired by round: median, 95 % interval and the
        number of rounds both were timed in; None with fewer than three such rounds."""
        step = next((s for (name, d), s in self.by_step.items()
                     if name == scenario and abs(d - dt) <= 1e-6 * dt), None)
        if step is None:
            return None
        try:
            a, b = step.xs(slower, level="label"), step.xs(faster, level="label")
        except KeyError:
            return None
        both = a.index.intersection(b.index)
        if len(both) < 3:
            return None
        median, lo, hi = bootstrap_median((a[both] / b[both]).to_numpy())
        return dict(median=median, lo=lo, hi=hi, rounds=len(both))


# the variant suffixes of rtp at the baseline instruction set (physbench-rtp-baseline)
BASELINE_SUFFIXES = ("-x86-64", "-baseline")
# the variant suffixes of a peer built for this machine's instruction set beside its generic build
# (workers/catalog.tsv: Rapier for the native CPU, Box2D v3 with its AVX2 path)
NATIVE_SUFFIXES = ("-native", "-avx2")


def format_ratio(r: dict | None) -> str:
    """"2.31× (2.20–2.45)" or "" when the pair was not timed in enough common rounds."""
    if r is None:
        return ""
    return f"{r['median']:.3g}× ({r['lo']:.3g}–{r['hi']:.3g})"


def rtp_against_peers(results: pd.DataFrame, paired: PairedRatios, defaults: dict[str, str]) -> list[dict]:
    """Per contact scenario at its own step: each peer's defaults against rtp's, as the peer's time
    per step over rtp's, paired by round (above 1: rtp is faster), with both verdicts; and the same
    against rtp's default at the baseline instruction set where the run has it (ratio_baseline)."""
    table = []
    for name, rows in results.groupby("scenario", sort=False):
        if "contact_verdict" not in rows or rows["contact_verdict"].isna().all():
            continue
        own = rows[[knob_suffix(r) == "" for _, r in rows.iterrows()]]
        rtp = own[(own["engine"] == "rtp") & (own["variant"] == defaults["rtp"])]
        if rtp.empty:
            continue
        rtp = rtp.iloc[0]
        # rtp's default at the baseline instruction set (physbench-rtp-baseline), where the run has it
        base = own[(own["engine"] == "rtp") & own["variant"].isin(
            [defaults["rtp"] + suffix for suffix in BASELINE_SUFFIXES])]
        base = base.iloc[0] if not base.empty else None
        peers = []
        for engine, variant in defaults.items():
            mine = own[(own["engine"] == engine) & (own["variant"] == variant)]
            if engine == "rtp" or mine.empty:
                continue
            peer = mine.iloc[0]
            r = paired.ratio(name, float(rtp["dt"]), peer["label"], rtp["label"])
            at_baseline = (format_ratio(paired.ratio(name, float(rtp["dt"]), peer["label"], base["label"]))
                           or "not timed in rounds") if base is not None else "not run"
            peers.append(dict(peer=peer["label"], ratio=format_ratio(r) or "not timed in rounds",
                              ratio_baseline=at_baseline,
                              verdict=peer.get("contact_verdict") if pd.notna(peer.get("contact_verdict"))
                              else peer["status"]))
        table.append(dict(scenario=name, rtp=rtp["label"], rtp_baseline=base["label"] if base is not None else None,
                          rtp_verdict=rtp.get("contact_verdict") if pd.notna(rtp.get("contact_verdict"))
                          else rtp["status"], peers=peers))
    return table
