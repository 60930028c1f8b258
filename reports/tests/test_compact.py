"""reports/compact.py: the trajectories as Parquet and back, the same numbers."""
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import compact  # noqa: E402
from physbench_report.load import read_trajectory  # noqa: E402


def trajectory() -> pd.DataFrame:
    rng = np.random.default_rng(3)
    n = 400
    return pd.DataFrame({
        "time": np.repeat(np.arange(n // 4) / 60.0, 4),
        "body": np.tile([1, 2, 3, 4], n // 4),
        # values whose decimal text needs all 17 digits, tiny ones, and an empty column
        "px": rng.standard_normal(n) * 1e-9 + 1.0 / 3.0,
        "qw": np.cos(rng.standard_normal(n)),
        "position_err": np.where(np.arange(n) % 7 == 0, np.nan, rng.random(n) * 1e-15),
        "stack_drift": np.full(n, np.nan),
    })


def test_a_trajectory_keeps_every_number_as_parquet_and_back_as_csv(tmp_path):
    folder = tmp_path / "run" / "trajectories"
    folder.mkdir(parents=True)
    original = trajectory()
    original.to_csv(folder / "s__rtp__rk4.csv", index=False)
    written = pd.read_csv(folder / "s__rtp__rk4.csv")
    assert compact.main([str(tmp_path / "run")]) == 0
    assert not (folder / "s__rtp__rk4.csv").exists()
    parquet = pd.read_parquet(folder / "s__rtp__rk4.parquet")
    assert compact.same_numbers(written, parquet)
    assert np.array_equal(parquet["px"].to_numpy(), original["px"].to_numpy())  # bit for bit
    # the report reads the row's CSV name from the Parquet file
    assert compact.same_numbers(written, read_trajectory(tmp_path / "run", "trajectories/s__rtp__rk4.csv"))
    # and the CSV comes back as an export
    assert compact.main([str(tmp_path / "run"), "--export-csv"]) == 0
    assert compact.same_numbers(written, pd.read_csv(folder / "s__rtp__rk4.csv"))


def test_same_numbers_tells_a_changed_value_apart():
    a = trajectory()
    b = a.copy()
    b.loc[5, "px"] = np.nextafter(b.loc[5, "px"], 2.0)  # one ulp
    assert compact.same_numbers(a, a.copy()) and not compact.same_numbers(a, b)


def test_a_folder_without_trajectories_is_refused(tmp_path, capsys):
    assert compact.main([str(tmp_path)]) == 2
    assert "no such folder" in capsys.readouterr().err
