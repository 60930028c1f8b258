"""Reading a results folder: results.csv (checked against harness/results-schema.json),
metadata.json, the benchmarks/*.json documents and the trajectories/*.csv series. Every file is
read once: a scenario's trajectories are read together, for all of its charts, by trajectories()."""
from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

# the error series a trajectory CSV may hold: column, title, unit, and the results.csv summary column
SERIES = [
    ("position_err", "Position error against the reference", "m", "position_err_max"),
    ("orientation_err", "Orientation error against the reference", "rad", "orientation_err_max"),
    ("stack_drift", "Stack drift: largest horizontal displacement of any body", "m", "stack_drift_max"),
    ("penetration", "Deepest penetration (rtp's narrow phase on the true shapes)", "m", "penetration_max"),
    ("energy_drift", "Relative energy drift |E − E₀| / (KE₀ + spring PE₀)", "", "energy_drift_max"),
    ("linear_momentum_drift", "Linear momentum drift |P − P₀|", "kg m/s", "linear_momentum_drift_max"),
    ("angular_momentum_drift", "Relative angular momentum drift |L − L₀| / |L₀|", "", "angular_momentum_drift_max"),
]


class ReportError(Exception):
    """A results folder that cannot be reported, with what is wrong and where."""


SCHEMA_FILE = Path(__file__).resolve().parents[2] / "harness" / "results-schema.json"


def check_schema(results: pd.DataFrame, csv: Path) -> None:
    """results.csv against harness/results-schema.json, the contract `physbench run` writes by: no
    column the schema lacks, every required column present and filled, numbers that parse. A column
    the schema has and the file lacks is allowed (a run from before the column joined)."""
    schema = json.loads(SCHEMA_FILE.read_text())
    columns = {c["name"]: c for c in schema["columns"]}
    unknown = [c for c in results.columns if c not in columns]
    if unknown:
        raise ReportError(f"{csv}: columns not in {SCHEMA_FILE.name}: {unknown}")
    for name, c in columns.items():
        if name not in results.columns:
            if c["required"]:
                raise ReportError(f"{csv}: missing column {name!r}, which every row must fill")
            continue
        values = results[name]
        filled = values.notna() & (values.astype(str) != "")
        if c["required"] and not filled.all():
            raise ReportError(f"{csv}: row {int((~filled).idxmax()) + 2}: {name} is empty")
        if c["type"] in ("number", "integer"):
            parsed = pd.to_numeric(values.where(filled), errors="coerce")
            wrong = filled & parsed.isna()
            if wrong.any():
                row = int(wrong.idxmax())
                raise ReportError(f"{csv}: row {row + 2}: {name} = {values[row]!r} is not a {c['type']}")
        if c["type"] == "status":
            wrong = filled & ~values.isin(schema["statuses"])
            if wrong.any():
                row = int(wrong.idxmax())
                raise ReportError(f"{csv}: row {row + 2}: status {values[row]!r} is not one of {schema['statuses']}")


def load_results(folder: Path) -> tuple[pd.DataFrame, dict]:
    """results.csv, checked against the schema, with a label column (engine/variant), and metadata.json."""
    csv = folder / "results.csv"
    meta = folder / "metadata.json"
    if not csv.is_file():
        raise ReportError(f"{csv}: missing (is {folder} a physbench results folder?)")
    if not meta.is_file():
        raise ReportError(f"{meta}: missing")
    try:
        results = pd.read_csv(csv, dtype={"message": str, "trajectory": str})
    except Exception as exc:  # pandas raises several types for a broken file
        raise ReportError(f"{csv}: unreadable: {exc}") from exc
    check_schema(results, csv)
    try:
        metadata = json.loads(meta.read_text())
    except json.JSONDecodeError as exc:
        raise ReportError(f"{meta}: not valid JSON: {exc}") from exc
    results["label"] = results["engine"] + "/" + results["variant"] + [knob_suffix(r) for _, r in results.iterrows()]
    return results, metadata


def knob_suffix(row) -> str:
    """A knob sweep's row (--sweep-iterations, --sweep-substeps) is one more configuration of its
    engine variant, labelled as such wherever rows are drawn or listed: " iterations=8"."""
    parts = [f"{knob}={int(row[knob])}" for knob in ("iterations", "substeps")
             if knob in row and pd.notna(row[knob])]
    return " " + " ".join(parts) if parts else ""


def is_swept(row) -> bool:
    """Whether a row ran at a swept solver knob rather than its variant's own settings."""
    return knob_suffix(row) != ""


def is_nominal(meta: dict, row) -> bool:
    """Whether a row ran at its scenario's own step (a swept scenario has rows at other steps too)."""
    own = meta.get("scenarios", {}).get(row["scenario"], {}).get("dt")
    return own is None or abs(row["dt"] - own) <= 1e-6 * own


def read_trajectory(folder: Path, name: str) -> pd.DataFrame:
    """A row's trajectory as physbench wrote it (trajectories/*.csv) or as reports/compact.py keeps
    it (the same name with .parquet: the same numbers)."""
    path = folder / name
    if not path.is_file() and path.with_suffix(".parquet").is_file():
        return pd.read_parquet(path.with_suffix(".parquet"))
    return pd.read_csv(path)


def trajectories(folder: Path, rows: pd.DataFrame) -> dict:
    """Each row's trajectory (trajectories/*.csv or *.parquet), read once for every chart drawn
    from it, by the row's index (rows without a trajectory are left out). A scenario's rows at a
    time: the default suite's trajectories together are far larger than one scenario's."""
    return {index: read_trajectory(folder, row["trajectory"]) for index, row in rows.iterrows()
            if isinstance(row.get("trajectory"), str)}


def families_of(meta: dict) -> dict[str, list[tuple]]:
    """Scenario families from the metadata: family -> [(parameter, scenario, info), ...]."""
    families: dict[str, list[tuple]] = {}
    for name, info in meta.get("scenarios", {}).items():
        if info.get("family"):
            families.setdefault(info["family"], []).append((info.get("parameter"), name, info))
    return families


def benchmark_document(folder: Path, name: str) -> dict | None:
    """A Google Benchmark JSON file bench.sh wrote into benchmarks/, or None when there is none."""
    path = folder / "benchmarks" / name
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ReportError(f"{path}: not valid JSON: {exc}") from exc
