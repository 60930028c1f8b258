"""The replay viewer's data: the runner's pose files and what the report embeds from them."""
from __future__ import annotations

import base64
import gzip
import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from support import physbench_run
import build_report  # noqa: E402  (found through support's path)
from physbench_report import replay  # noqa: E402


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> Path:
    return physbench_run(tmp_path_factory.mktemp("replay") / "r", "-s", "tower-10,tumbling-box,particles-plume",
                         "-e", "rtp,ode", "--no-sweep", "--duration", "0.5")


def ok_rows(folder: Path) -> pd.DataFrame:
    table = pd.read_csv(folder / "results.csv")
    return table[table["trajectory"].notna()]


def test_every_run_at_its_own_step_has_a_pose_file_matching_its_trajectory(run):
    rows = ok_rows(run)
    assert len(rows) >= 4
    total = 0
    for _, row in rows.iterrows():
        path = run / "poses" / (Path(row["trajectory"]).stem + ".bin")
        index, times, poses = replay.read_pose_file(path)[:3]
        total += path.stat().st_size
        traj = pd.read_csv(run / row["trajectory"])
        # the CSV keeps at most eight bodies' states (four on a contact scene), the first and last
        # probed among them, and the
        # first four probed particles (results_folder.cpp, kTrajectoryBodies and kCsvParticles);
        # the pose file every probed body
        csv_bodies = sorted(traj["body"].unique())
        if row["scenario"].startswith("particles-"):
            assert len(index) == 200 and csv_bodies == sorted(index)[:4]
        else:
            most = 4 if row["scenario"].startswith("tower") else 8
            assert len(csv_bodies) == min(most, len(index)) and set(csv_bodies) <= set(index)
            assert csv_bodies[0] == min(index) and csv_bodies[-1] == max(index)
        kept = [list(index).index(b) for b in csv_bodies]
        index, poses = index[kept], poses[:, kept]
        # 30 frames per simulated second from 60 Hz samples, or every k-th sample where the job cap
        # (96 KiB) needs it (200 particles: one in 3), evenly; the last sample included
        spacing = np.diff(times)
        assert np.allclose(spacing[:-1], spacing[0], atol=1e-5) and spacing[-1] <= spacing[0] + 1e-5
        assert spacing[0] == pytest.approx(1 / 30, abs=1e-5) or row["scenario"].startswith("particles-")
        samples = round(spacing[0] * 60)
        assert samples >= 2 and spacing[0] == pytest.approx(samples / 60, abs=1e-5)
        assert times[-1] == pytest.approx(traj["time"].max(), abs=1e-6)
        # frame k is the trajectory's sample at that time, to float32 precision
        for k in (0, len(times) // 2, len(times) - 1):
            at = traj[np.isclose(traj["time"], times[k], atol=1e-5)].set_index("body").loc[index]
            expected = at[["px", "py", "pz", "qx", "qy", "qz", "qw"]].to_numpy(float)
            got = poses[k, :, :7].astype(float)
            flip = np.sum(expected[:, 3:] * got[:, 3:], axis=1) < 0  # q and −q are one rotation
            got[flip, 3:] *= -1
            assert np.allclose(got, expected, rtol=1e-6, atol=1e-6)
            speed = np.linalg.norm(at[["vx", "vy", "vz"]].to_numpy(float), axis=1)
            assert np.allclose(poses[k, :, 7], speed, rtol=1e-5, atol=1e-6)
    meta = json.loads((run / "metadata.json").read_text())["poses"]
    assert meta["files"] == len(rows) and meta["bytes"] == total
    assert meta["bytes_per_run_cap"] >= meta["bytes_per_job_cap"] > 0


def test_a_particle_mode_records_a_sample_of_its_particles(run):
    rows = ok_rows(run)
    row = rows[rows["scenario"] == "particles-plume"].iloc[0]
    recorded = replay.read_pose_file(run / "poses" / (Path(row["trajectory"]).stem + ".bin"))
    index, poses = recorded.index, recorded.poses
    assert recorded.contacts is None  # particles against planes: not a contact scene
    scene = json.loads((run / "scenes" / "particles-plume.json").read_text())
    assert len(index) == 200 and index.min() >= len(scene["bodies"])  # particles follow the bodies
    # spread over the set: the sample covers the spawn square, not one corner of it
    assert np.ptp(poses[0, :, 0]) > 6 and np.ptp(poses[0, :, 2]) > 6


def embedded(page: str) -> dict:
    blocks = re.findall(r'<script type="application/json" id="(replay-\d+)">(.*?)</script>', page, re.S)
    out = {}
    for _, text in blocks:
        data = json.loads(text.replace("<\\/", "</"))
        out[data["name"]] = data
    return out


def unpack(text: str, dtype) -> np.ndarray:
    return np.frombuffer(gzip.decompress(base64.b64decode(text)), dtype)


def test_the_report_embeds_each_engines_replay_and_the_viewer(run):
    page = build_report.build_report(run).read_text()
    assert "physbenchReplays" in page  # the bundled viewer (three.js inside)
    data = embedded(page)
    assert set(data) == {"tower-10", "tumbling-box", "particles-plume"}
    tower = data["tower-10"]
    assert {r["engine"] for r in tower["runs"]} == {"rtp", "ode"}
    assert any(s["shape"]["type"] == "plane" for s in tower["static"])  # the ground
    assert len(tower["shapes"]) == 10
    assert data["particles-plume"]["particles"]["attractors"]  # drawn as the force point
    # what the viewer decodes is the pose file, to float16 on the offsets from frame 0
    rows = ok_rows(run)
    for name, scene in data.items():
        for r in scene["runs"]:
            row = rows[(rows["scenario"] == name) & (rows["engine"] + "/" + rows["variant"] == r["label"])].iloc[0]
            recorded = replay.read_pose_file(run / "poses" / (Path(row["trajectory"]).stem + ".bin"))
            times, poses = recorded.times, recorded.poses
            frames, bodies = r["frames"], len(r["bodies"])
            assert frames == len(times)
            got = unpack(r["poses"], "<f2").astype(np.float32).reshape(frames, bodies, 8)
            got[:, :, :3] += unpack(r["origin"], "<f4").reshape(bodies, 3)
            assert np.allclose(unpack(r["times"], "<f4"), times)
            offset = np.abs(poses[:, :, :3] - poses[:1, :, :3]).max()
            assert np.allclose(got[:, :, :3], poses[:, :, :3], atol=1e-3 * max(1.0, offset))
            assert np.allclose(got[:, :, 3:7], poses[:, :, 3:7], atol=1e-3)
            # a contact scene's depths and points, every frame here (float16: 1e-3 relative)
            assert ("depth" in r) == (recorded.depth is not None) == ("contacts" in r)
            if recorded.depth is None:
                continue
            assert recorded.contact_stride == 1
            assert np.array_equal(unpack(r["contact_frames"], "<u4"), np.arange(frames))
            depth = unpack(r["depth"], "<f2").astype(np.float32).reshape(frames, bodies)
            assert np.allclose(depth, recorded.depth, rtol=1e-3, atol=1e-7)
            assert np.array_equal(unpack(r["contact_counts"], "<u4"), recorded.contact_counts)
            points = unpack(r["contacts"], "<f2").astype(np.float32).reshape(4, -1).T  # columns
            assert np.allclose(points, recorded.contacts, rtol=1e-3, atol=1e-3)


def test_a_scene_over_its_budget_keeps_fewer_frames_and_says_so(run, monkeypatch):
    full = replay.replays(run, pd.read_csv(run / "results.csv"), json.loads((run / "metadata.json").read_text()))
    size = len(full["tower-10"]["json"])
    monkeypatch.setattr(replay, "SCENE_BYTES", size // 3)
    cut = replay.replays(run, pd.read_csv(run / "results.csv"), json.loads((run / "metadata.json").read_text()))
    data = json.loads(cut["tower-10"]["json"])
    assert "one recorded frame in" in cut["tower-10"]["note"]
    assert data["runs"][0]["frames"] < json.loads(full["tower-10"]["json"])["runs"][0]["frames"]
    assert sum(len(r["poses"]) + len(r["times"]) + len(r["origin"]) for r in data["runs"]) <= size // 3


def test_contacts_take_their_own_budget_and_never_a_pose_frame(run, monkeypatch):
    results, meta = pd.read_csv(run / "results.csv"), json.loads((run / "metadata.json").read_text())
    full = json.loads(replay.replays(run, results, meta)["tower-10"]["json"])
    contacts = sum(len(r["contacts"]) + len(r["contact_counts"]) + len(r["depth"]) + len(r["contact_frames"])
                   for r in full["runs"])
    # room for about half of them: one contact frame in 2 or more, the poses as they were
    monkeypatch.setattr(replay, "CONTACT_SCENE_BYTES", contacts // 2)
    half = replay.replays(run, results, meta)["tower-10"]
    data = json.loads(half["json"])
    for whole, cut in zip(full["runs"], data["runs"]):
        assert cut["poses"] == whole["poses"] and cut["frames"] == whole["frames"]
        shown = unpack(cut["contact_frames"], "<u4")
        assert 1 < len(shown) <= (whole["frames"] + 1) // 2 and shown[0] == 0
    assert "contacts and penetration at about" in half["note"]
    # no room: no contacts, and the note says so
    monkeypatch.setattr(replay, "CONTACT_PAGE_BYTES", 100)
    none = replay.replays(run, results, meta)["tower-10"]
    assert "no contacts" in none["note"] and "contacts" not in json.loads(none["json"])["runs"][0]


def test_past_the_page_budget_a_scene_gets_a_note_not_a_viewer(run, monkeypatch):
    full = replay.replays(run, pd.read_csv(run / "results.csv"), json.loads((run / "metadata.json").read_text()))
    first = next(name for name in replay.REPLAY_SCENES if name in full)
    monkeypatch.setattr(replay, "PAGE_BYTES", full[first]["bytes"])
    page = build_report.build_report(run).read_text()
    assert list(embedded(page)) == [first]  # the first scene takes the whole budget
    assert f"not embedded: the page&#39;s replays reached {full[first]['bytes']:,} bytes" in page


def test_without_the_bundle_the_page_says_how_to_build_it(run, monkeypatch, tmp_path):
    monkeypatch.setattr(replay, "VIEWER_JS", tmp_path / "absent.js")
    page = build_report.build_report(run).read_text()
    assert "The replay viewer is not built" in page
    assert "physbenchReplays" not in page


def test_a_contact_scene_records_its_contacts_with_its_poses(run):
    rows = ok_rows(run)
    towers = rows[rows["scenario"] == "tower-10"]
    assert len(towers) >= 2
    scene = json.loads((run / "scenes" / "tower-10.json").read_text())
    assert scene["gravity"][1] < 0  # y is up
    for _, row in towers.iterrows():
        recorded = replay.read_pose_file(run / "poses" / (Path(row["trajectory"]).stem + ".bin"))
        label = f"{row['engine']}/{row['variant']}"
        frames, bodies = recorded.poses.shape[:2]
        assert recorded.contact_stride == 1  # a short tower's contacts fit beside every frame
        assert recorded.depth.shape == (frames, bodies) and len(recorded.contact_counts) == frames
        # frame 0 is the scene as built: ten unit boxes stacked exactly touching on the ground,
        # so ten touching pairs of four corners each, all at depth 0, at whole-metre heights
        start = recorded.contacts_of(0)
        assert len(start) == 40, label
        assert np.allclose(start[:, 3], 0, atol=1e-6)
        assert np.allclose(np.abs(start[:, [0, 2]]), 0.5, atol=1e-6)
        assert sorted(np.round(start[:, 1]).astype(int)) == sorted(list(range(10)) * 4)
        assert np.allclose(start[:, 1], np.round(start[:, 1]), atol=1e-6)
        # each frame's deepest body is the penetration metric's sample at that time
        traj = pd.read_csv(run / row["trajectory"]).groupby("time")["penetration"].first()
        metric = traj.to_numpy()[np.searchsorted(traj.index.to_numpy(), recorded.times - 1e-6)]
        assert np.allclose(recorded.depth.max(axis=1), metric, rtol=1e-5, atol=1e-7), label
        # no contact point is deeper than the deepest body of its frame
        for k in range(frames):
            points = recorded.contacts_of(k)
            assert len(points) == 0 or points[:, 3].max() <= recorded.depth[k].max() * (1 + 1e-6) + 1e-9
        # after the first frame the stack has settled into the ground somewhat: depth is not all zero
        assert recorded.depth[1:].max() > 0, label


def pose_header(magic: bytes, frames: int, bodies: int, *words: int) -> bytes:
    return magic + np.array([frames, bodies], "<u4").tobytes() + np.array([1 / 30], "<f4").tobytes() + \
        np.array(words, "<u4").tobytes()


def test_a_pose_file_from_before_contacts_is_still_read(tmp_path):
    path = tmp_path / "old.bin"
    poses = np.arange(2 * 1 * 8, dtype="<f4")
    path.write_bytes(pose_header(b"PBPOSES1", 2, 1, 0) + np.array([1], "<i4").tobytes()
                     + np.array([0, 1 / 30], "<f4").tobytes() + poses.tobytes())
    recorded = replay.read_pose_file(path)
    assert recorded.poses.shape == (2, 1, 8) and recorded.poses[1, 0, 7] == 15
    assert recorded.contacts is None and recorded.depth is None


def test_contacts_every_third_frame_are_read_at_their_frames(tmp_path):
    # 5 frames of 1 body, contacts at frames 0 and 3 (stride 3): 2 points, then 1
    path = tmp_path / "c.bin"
    path.write_bytes(pose_header(b"PBPOSES2", 5, 1, replay.SECTION_CONTACTS, 3, 3) + np.array([1], "<i4").tobytes()
                     + np.arange(5, dtype="<f4").tobytes() + np.zeros(5 * 8, "<f4").tobytes()
                     + np.array([0.01, 0.02], "<f4").tobytes() + np.array([2, 1], "<u4").tobytes()
                     + np.arange(12, dtype="<f4").tobytes())
    recorded = replay.read_pose_file(path)
    assert list(recorded.contact_frames) == [0, 3]
    assert recorded.depth[:, 0].tolist() == pytest.approx([0.01, 0.02])
    assert recorded.contacts_of(1).tolist() == [[8, 9, 10, 11]]
    # the page keeps one frame in 2 (0, 2, 4): only kept frame 0 has contacts recorded
    encoded = replay.encode_contacts(recorded, replay.frames_every(5, 2), 1)
    assert unpack(encoded["contact_frames"], "<u4").tolist() == [0]
    assert unpack(encoded["contact_counts"], "<u4").tolist() == [2]


def test_a_truncated_pose_file_is_named(tmp_path):
    path = tmp_path / "x.bin"
    path.write_bytes(pose_header(b"PBPOSES1", 2, 1, 0))
    with pytest.raises(replay.PoseFileError, match="header says"):
        replay.read_pose_file(path)
    # contact sections promised by the header but not there
    path.write_bytes(pose_header(b"PBPOSES2", 1, 1, replay.SECTION_CONTACTS, 4, 1) + bytes(4 + 4 + 32))
    with pytest.raises(replay.PoseFileError, match="header says"):
        replay.read_pose_file(path)
