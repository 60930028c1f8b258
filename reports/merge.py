"""Joins the results folders of a sharded run into one (`physbench merge -o OUT SHARD_DIR...`).

`physbench run --shard K/N` runs the jobs of the plan whose number is K-1 modulo N and records in
metadata.json the plan's fingerprint, the shard and each row's job number. This joins N such
folders: it refuses folders of different plans, builds or commits, a missing or repeated shard and
an unfinished run, then writes OUT with the rows in plan order (what the unsharded run writes),
every trajectory, scene and pose file, and one metadata.json. As `physbench run`, it writes only
into a new or empty folder, and results.csv appears last, complete (docs/regression.md).
"""
from __future__ import annotations

import argparse
import csv
import filecmp
import json
import shutil
import sys
from pathlib import Path

FOLDERS = ("scenes", "trajectories", "poses")


class MergeError(Exception):
    pass


def read_shard(folder: Path) -> dict:
    if not folder.is_dir():
        raise MergeError(f"{folder}: no such folder")
    if (folder / "INCOMPLETE").exists() or not (folder / "results.csv").exists():
        raise MergeError(f"{folder}: not a finished run (no results.csv)")
    try:
        metadata = json.loads((folder / "metadata.json").read_text())
    except (OSError, json.JSONDecodeError) as e:
        raise MergeError(f"{folder}/metadata.json: cannot be read: {e}") from e
    plan = metadata.get("plan")
    if not isinstance(plan, dict) or "fingerprint" not in plan or "row_jobs" not in plan:
        raise MergeError(f"{folder}/metadata.json: no plan (made by a physbench without --shard?)")
    with open(folder / "results.csv", newline="") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        rows = list(reader)
    if header is None:
        raise MergeError(f"{folder}/results.csv: empty")
    if len(rows) != len(plan["row_jobs"]):
        raise MergeError(f"{folder}: results.csv has {len(rows)} rows but metadata.json's plan.row_jobs "
                         f"numbers {len(plan['row_jobs'])}")
    return {"folder": folder, "metadata": metadata, "plan": plan, "header": header, "rows": rows}


def check_together(shards: list[dict]) -> int:
    """The shards' count N, once they are shown to be the N slices of one plan, one build."""
    first = shards[0]
    for s in shards[1:]:
        if s["plan"]["fingerprint"] != first["plan"]["fingerprint"]:
            raise MergeError(f"{s['folder']} ran another plan than {first['folder']} (plan fingerprint "
                             f"{s['plan']['fingerprint']} against {first['plan']['fingerprint']}): "
                             "shards must come from one command line")
    for key in ("git_commit", "build", "compiler"):
        for s in shards[1:]:
            if s["metadata"].get(key) != first["metadata"].get(key):
                raise MergeError(f"{s['folder']} was built differently from {first['folder']} "
                                 f"({key}: {s['metadata'].get(key)!r} against {first['metadata'].get(key)!r})")
    for s in shards[1:]:
        if s["header"] != first["header"]:
            raise MergeError(f"{s['folder']}/results.csv has other columns than {first['folder']}'s")
    count = first["plan"]["shard"]["count"]
    seen: dict[int, Path] = {}
    for s in shards:
        shard = s["plan"]["shard"]
        if shard["count"] != count:
            raise MergeError(f"{s['folder']} is shard {shard['index']}/{shard['count']}, "
                             f"{first['folder']} one of {count}")
        if shard["index"] in seen:
            raise MergeError(f"shard {shard['index']}/{count} given twice: {seen[shard['index']]} "
                             f"and {s['folder']}")
        seen[shard["index"]] = s["folder"]
    missing = [k for k in range(1, count + 1) if k not in seen]
    if missing:
        raise MergeError("missing shard(s) " + ", ".join(f"{k}/{count}" for k in missing))
    return count


def deep_merge(into: dict, other: dict) -> None:
    for key, value in other.items():
        if isinstance(value, dict) and isinstance(into.get(key), dict):
            deep_merge(into[key], value)
        else:
            into.setdefault(key, value)


def merged_metadata(shards: list[dict]) -> dict:
    out = json.loads(json.dumps(shards[0]["metadata"]))
    for s in shards[1:]:
        m = s["metadata"]
        deep_merge(out.setdefault("engines", {}), m.get("engines", {}))
        deep_merge(out.setdefault("scenarios", {}), m.get("scenarios", {}))
        poses, theirs = out.get("poses"), m.get("poses")
        if isinstance(poses, dict) and isinstance(theirs, dict):
            poses["files"] = poses.get("files", 0) + theirs.get("files", 0)
            poses["bytes"] = poses.get("bytes", 0) + theirs.get("bytes", 0)
            poses.setdefault("not_written", {}).update(theirs.get("not_written", {}))
    out["created"] = min(s["metadata"].get("created", "") for s in shards)
    out["command"] = [s["metadata"].get("command", "") for s in shards]
    machines = [s["metadata"].get("machine") for s in shards]
    if any(machine != machines[0] for machine in machines):
        out["machine"] = machines  # speed ratios hold within a shard only: say so by listing them
    jobs = sorted(j for s in shards for j in s["plan"]["row_jobs"])
    out["plan"] = {"fingerprint": shards[0]["plan"]["fingerprint"], "jobs": shards[0]["plan"]["jobs"],
                   "shard": {"index": 1, "count": 1}, "jobs_in_shard": shards[0]["plan"]["jobs"],
                   "row_jobs": jobs,
                   "merged_from": [{"folder": str(s["folder"]), "shard": s["plan"]["shard"],
                                    "created": s["metadata"].get("created"),
                                    "hostname": (s["metadata"].get("machine") or {}).get("hostname")}
                                   for s in shards]}
    return out


def merge(out: Path, folders: list[Path]) -> int:
    if not folders:
        raise MergeError("no shard folders given")
    shards = [read_shard(Path(f)) for f in folders]
    check_together(shards)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise MergeError(f"the results folder {out} already holds files: merge writes only into a new "
                         "or empty folder; choose another -o")
    out.mkdir(parents=True, exist_ok=True)
    for s in shards:
        for name in FOLDERS:
            source = s["folder"] / name
            if not source.is_dir():
                continue
            (out / name).mkdir(exist_ok=True)
            for f in source.iterdir():
                target = out / name / f.name
                if target.exists():
                    # a scene (and its reference) whose jobs fell in two shards: written twice, alike
                    if not filecmp.cmp(f, target, shallow=False):
                        raise MergeError(f"{f} differs from the same file of another shard")
                    continue
                shutil.copy2(f, target)
    rows = sorted((job, row) for s in shards for job, row in zip(s["plan"]["row_jobs"], s["rows"]))
    (out / "metadata.json.partial").write_text(json.dumps(merged_metadata(shards), indent=2) + "\n")
    with open(out / "results.csv.partial", "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(shards[0]["header"])
        writer.writerows(row for _, row in rows)
    # each shard's timing rounds (a scene step is in one shard only, so none repeats)
    timed = [s["folder"] / "timing_rounds.csv" for s in shards if (s["folder"] / "timing_rounds.csv").is_file()]
    if timed:
        with open(out / "timing_rounds.csv", "w", newline="") as f:
            for i, source in enumerate(timed):
                lines = source.read_text().splitlines(keepends=True)
                f.writelines(lines if i == 0 else lines[1:])
    (out / "metadata.json.partial").rename(out / "metadata.json")
    (out / "results.csv.partial").rename(out / "results.csv")
    return len(rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="physbench merge", description=__doc__.split("\n\n")[0])
    parser.add_argument("-o", "--out", required=True, type=Path, help="the merged results folder (new or empty)")
    parser.add_argument("shards", nargs="+", type=Path, help="the N folders of `physbench run --shard K/N`")
    args = parser.parse_args(argv)
    try:
        rows = merge(args.out, args.shards)
    except MergeError as e:
        print(f"physbench merge: {e}", file=sys.stderr)
        return 2
    print(f"merged {len(args.shards)} shards, {rows} rows: {args.out.resolve()}/results.csv")
    return 0


if __name__ == "__main__":
    sys.exit(main())
