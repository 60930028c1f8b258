"""Keeps a results folder's trajectories as Parquet: `reports/compact.py RUN` writes each
trajectories/*.csv as trajectories/*.parquet (zstd; the float columns byte-stream split, every
value the float64 the CSV held), reads it back, checks it holds the same numbers, and only then
removes the CSV. `reports/compact.py --export-csv RUN` writes the CSVs back from the Parquet files
(every value as the shortest text that reads back to the same float64). The report reads either.

One line in the field's tools reads them all, e.g. DuckDB:
    SELECT * FROM 'RUN/trajectories/*.parquet'
or pandas: pd.read_parquet('RUN/trajectories/tower-20__rtp__soft-step.parquet').
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

COMPRESSION = "zstd"
LEVEL = 9  # zstd's level: the suite's trajectories in about a second more than level 3, smaller


class CompactError(Exception):
    pass


def same_numbers(a: pd.DataFrame, b: pd.DataFrame) -> bool:
    """The same columns, in order, and every value the same (NaN where the other has NaN)."""
    if list(a.columns) != list(b.columns) or len(a) != len(b):
        return False
    for column in a.columns:
        x, y = a[column].to_numpy(), b[column].to_numpy()
        if x.dtype.kind == "f" or y.dtype.kind == "f":
            x, y = x.astype(np.float64), y.astype(np.float64)
            if not np.array_equal(x, y, equal_nan=True):
                return False
        elif not np.array_equal(x, y):
            return False
    return True


def to_parquet(csv: Path) -> Path:
    """csv as a Parquet file beside it, checked, then the CSV removed; the Parquet file's path."""
    try:
        frame = pd.read_csv(csv)
    except Exception as exc:  # pandas raises several types for a broken file
        raise CompactError(f"{csv}: unreadable: {exc}") from exc
    table = pa.Table.from_pandas(frame, preserve_index=False)
    floats = [f.name for f in table.schema if pa.types.is_floating(f.type)]
    target = csv.with_suffix(".parquet")
    partial = target.with_suffix(".parquet.partial")
    pq.write_table(table, partial, compression=COMPRESSION, compression_level=LEVEL,
                   use_byte_stream_split=floats or False, use_dictionary=False)
    if not same_numbers(frame, pd.read_parquet(partial)):
        partial.unlink()
        raise CompactError(f"{csv}: the Parquet file does not read back to the same numbers; the CSV is kept")
    partial.replace(target)
    csv.unlink()
    return target


def to_csv(parquet: Path) -> Path:
    """parquet's table as a CSV beside it (the shortest round-trip text for each float)."""
    frame = pd.read_parquet(parquet)
    target = parquet.with_suffix(".csv")
    frame.to_csv(target, index=False)
    if not same_numbers(frame, pd.read_csv(target)):
        raise CompactError(f"{target}: does not read back to {parquet}'s numbers")
    return target


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run", type=Path, help="a results folder (physbench run's --out)")
    parser.add_argument("--export-csv", action="store_true",
                        help="write trajectories/*.csv back from the Parquet files (which stay)")
    args = parser.parse_args(argv)
    folder = args.run / "trajectories"
    if not folder.is_dir():
        print(f"compact: {folder}: no such folder (is {args.run} a results folder?)", file=sys.stderr)
        return 2
    try:
        if args.export_csv:
            done = [to_csv(p) for p in sorted(folder.glob("*.parquet"))]
            print(f"compact: {len(done)} trajectories written as CSV in {folder}")
            return 0
        before = sum(p.stat().st_size for p in folder.glob("*.csv"))
        done = [to_parquet(p) for p in sorted(folder.glob("*.csv"))]
        after = sum(p.stat().st_size for p in done)
    except CompactError as exc:
        print(f"compact: {exc}", file=sys.stderr)
        return 1
    print(f"compact: {len(done)} trajectories, {before / 1e6:.1f} MB of CSV -> {after / 1e6:.1f} MB of Parquet")
    return 0


if __name__ == "__main__":
    sys.exit(main())
