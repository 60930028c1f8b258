"""What a results folder keeps of each run's trajectory (docs/usage.md, "The results folder"): by
default the rows the report draws over time, each with at most four bodies' states on a contact scene
(eight on a free-motion one, whose chart draws each body's error), and per-sample
columns that still come from every probed body; `--all-trajectories` keeps everything."""
from __future__ import annotations

from pathlib import Path

import json

import numpy as np
import pandas as pd
import pytest

from support import physbench_run
from physbench_report import scenarios  # noqa: E402  (found through support's path)

ARGS = ("-s", "pyramid-10", "-e", "rtp", "--variant", "soft-step", "--duration", "0.5",
        "--sweep-substeps", "2")


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> tuple[Path, Path]:
    base = tmp_path_factory.mktemp("trajectories")
    return (physbench_run(base / "default", *ARGS, "--no-sweep"),
            physbench_run(base / "all", *ARGS, "--no-sweep", "--all-trajectories"))


def rows(folder: Path) -> pd.DataFrame:
    return pd.read_csv(folder / "results.csv", dtype={"trajectory": str})


def test_a_default_run_keeps_the_drawn_rows_trajectory_with_four_bodies_states(runs):
    default, everything = runs
    table = rows(default)
    own = table[table["substeps"].isna()]
    swept = table[table["substeps"].notna()]
    assert len(own) == 1 and len(swept) == 1
    # the swept row keeps its metrics, not a trajectory; with --all-trajectories it has one
    assert swept["trajectory"].isna().all() and swept["stack_drift_max"].notna().all()
    assert rows(everything)["trajectory"].notna().all()
    kept = pd.read_csv(default / own["trajectory"].iloc[0])
    full = pd.read_csv(everything / rows(everything).query("substeps != substeps")["trajectory"].iloc[0])
    probed = sorted(full["body"].unique())
    assert len(probed) == 55  # every box of the 10-row pyramid
    # four of them, spread evenly from the first to the last (the bottom row's first, the top)
    bodies = sorted(kept["body"].unique())
    assert len(bodies) == 4 and bodies[0] == probed[0] and bodies[-1] == probed[-1]
    gaps = np.diff([probed.index(b) for b in bodies])
    assert gaps.max() - gaps.min() <= 1
    # the kept bodies' states are the full run's, number for number
    states = ["px", "py", "pz", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz"]
    same = full[full["body"].isin(bodies)].reset_index(drop=True)
    pd.testing.assert_frame_equal(kept[["time", "body"] + states], same[["time", "body"] + states])
    # the per-sample columns come from every probed body, not from the kept four
    for column in ("stack_drift", "penetration", "energy_change_j"):
        assert (kept.groupby("time")[column].first().to_numpy()
                == pytest.approx(full.groupby("time")[column].first().to_numpy(), rel=0, abs=0)), column
    meta = json.loads((default / "metadata.json").read_text())
    assert "4 on a contact scene" in meta["trajectories"]["bodies"]


def test_the_harness_energy_column_is_the_energy_of_every_probed_bodys_state(runs):
    """E(t) − E(0) as the harness writes it against the report's own sum over the full states."""
    _, everything = runs
    row = rows(everything).query("substeps != substeps").iloc[0]
    full = pd.read_csv(everything / row["trajectory"])
    meta = json.loads((everything / "metadata.json").read_text())
    scene = scenarios.scene_of(everything, meta["scenarios"]["pyramid-10"])
    energy = scenarios.mechanical_energy(full, scene).sort_index()
    from_states = (energy - energy.iloc[0]).to_numpy()
    written = full.groupby("time", sort=True)["energy_change_j"].first().to_numpy()
    assert np.abs(written).max() > 0  # the pyramid settles: its energy moves
    assert written == pytest.approx(from_states, rel=1e-9, abs=1e-9 * np.abs(energy).max())
    # and the chart draws the harness's column
    assert scenarios.per_time(full, "energy_drift", scene).to_numpy() == pytest.approx(written, rel=0, abs=0)
