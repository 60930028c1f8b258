"""The report's 3D replay viewer: per chosen scene, each engine's pose file (poses/*.bin, written
by `physbench run`) and the scene's shapes, packed into a JSON block the bundled viewer
(reports/viewer/, three.js) draws. docs/viewer.md describes the files and the caps."""
from __future__ import annotations

import base64
import gzip
import json
from pathlib import Path
from typing import NamedTuple

import numpy as np

# the scenes that get a viewer, in the order they take the page's budget
REPLAY_SCENES = ["tower-20", "pyramid-20", "rain", "tumbling-box", "spring-cube", "particles-attractors",
                 "particles-plume", "particles-snow", "tower-10", "pyramid-10"]
# compressed pose bytes one scene's viewer may embed (frames are dropped evenly to fit)
SCENE_BYTES = 600_000
# all the viewers of one page; a scene past it gets a note instead of a viewer
PAGE_BYTES = 2_200_000
# the contacts' own budgets, on top of the poses' (contact points compress worse than poses: a
# pyramid-20's every contact point is 3.4 MB for nine engines), so contacts never cost a pose frame
# or a scene its viewer, and a full page of poses still leaves them room
CONTACT_SCENE_BYTES = 250_000
CONTACT_PAGE_BYTES = 700_000
# the variant each engine is shown in (its default); an engine not named shows its first row
SHOWN_VARIANTS = {"rtp": ["soft-step", "rk4", "midpoint"], "bullet": ["float"], "ode": ["quickstep"], "box2d": ["default"],
                  "mujoco": ["euler"], "box2d-v3": ["default"], "rapier": ["default"]}
FLOATS = 8  # px py pz qx qy qz qw |v|
CONTACT_FLOATS = 4  # x y z depth
SECTION_CONTACTS = 1  # the header's sections bit: contact sections follow the poses
MAGIC = b"PBPOSES2"
MAGIC_1 = b"PBPOSES1"  # before contacts: a 24-byte header and poses only (still read)
VIEWER_JS = Path(__file__).resolve().parents[1] / "viewer" / "dist" / "viewer.js"


class PoseFileError(Exception):
    pass


class PoseFile(NamedTuple):
    """A pose file's arrays. Contacts are recorded at the contact frames, frames 0, S, 2S, … for
    the contact stride S (None, 0: no contacts recorded); j below counts contact frames."""
    index: np.ndarray  # [B] scene body indices
    times: np.ndarray  # [F] s
    poses: np.ndarray  # [F, B, 8] px py pz qx qy qz qw |v|
    contact_stride: int
    depth: np.ndarray | None  # [Fc, B] each body's deepest penetration (m)
    contact_counts: np.ndarray | None  # [Fc] contact points per contact frame
    contacts: np.ndarray | None  # [C, 4] x y z depth, contact frame by contact frame

    @property
    def contact_frames(self) -> np.ndarray:
        """The frames that carry contacts [Fc]."""
        return np.arange(0, len(self.times), self.contact_stride) if self.contact_stride else np.zeros(0, int)

    def contacts_of(self, j: int) -> np.ndarray:
        """Contact frame j's points [n, 4] (x y z depth)."""
        start = int(self.contact_counts[:j].sum())
        return self.contacts[start:start + int(self.contact_counts[j])]


def read_pose_file(path: Path) -> PoseFile:
    """A pose file (docs/viewer.md): PBPOSES2, or PBPOSES1 from before contacts were recorded."""
    raw = path.read_bytes()
    if len(raw) >= 24 and raw[:8] == MAGIC_1:
        header, sections, points, stride = 24, 0, 0, 0
    elif len(raw) >= 32 and raw[:8] == MAGIC:
        header = 32
        sections, points, stride = (int(v) for v in np.frombuffer(raw, "<u4", 3, 20))
    else:
        raise PoseFileError(f"{path}: not a physbench pose file")
    frames, bodies = (int(v) for v in np.frombuffer(raw, "<u4", 2, 8))
    contacts = bool(sections & SECTION_CONTACTS)
    if contacts and stride == 0:
        raise PoseFileError(f"{path}: contact sections with a contact stride of 0")
    contact_frames = -(-frames // stride) if contacts else 0
    want = header + 4 * bodies + 4 * frames + 4 * FLOATS * frames * bodies
    if contacts:
        want += 4 * contact_frames * bodies + 4 * contact_frames + 4 * CONTACT_FLOATS * points
    if len(raw) != want:
        raise PoseFileError(f"{path}: {len(raw)} bytes, the header says {want}")
    at = header

    def take(dtype: str, count: int) -> np.ndarray:
        nonlocal at
        array = np.frombuffer(raw, dtype, count, at)
        at += 4 * count
        return array

    index = take("<i4", bodies)
    times = take("<f4", frames)
    poses = take("<f4", frames * bodies * FLOATS).reshape(frames, bodies, FLOATS)
    if not contacts:
        return PoseFile(index, times, poses, 0, None, None, None)
    depth = take("<f4", contact_frames * bodies).reshape(contact_frames, bodies)
    counts = take("<u4", contact_frames)
    if int(counts.sum()) != points:
        raise PoseFileError(f"{path}: the frames hold {int(counts.sum())} contact points, the header says {points}")
    return PoseFile(index, times, poses, stride, depth, counts,
                    take("<f4", points * CONTACT_FLOATS).reshape(points, CONTACT_FLOATS))


def packed(array: np.ndarray) -> str:
    return base64.b64encode(gzip.compress(np.ascontiguousarray(array).tobytes(), compresslevel=6, mtime=0)).decode()


def halves(array: np.ndarray) -> np.ndarray:
    with np.errstate(over="ignore"):
        return array.astype("<f2")


def encode_run(pose_file: PoseFile, keep: np.ndarray) -> dict:
    """One engine's frames `keep`: times as float32, positions as float16 offsets from the first
    frame (so a body at rest keeps sub-millimetre detail far from the origin), the rest float16."""
    chosen = pose_file.poses[keep].astype(np.float32)
    origin = np.nan_to_num(chosen[0, :, 0:3].copy(), nan=0.0, posinf=0.0, neginf=0.0)
    chosen[:, :, 0:3] -= origin
    return dict(frames=int(len(keep)), times=packed(pose_file.times[keep].astype("<f4")),
                origin=packed(origin.astype("<f4")), poses=packed(halves(chosen)))


def encode_contacts(pose_file: PoseFile, keep: np.ndarray, step: int) -> dict:
    """The contacts of every step-th kept frame that has them: which kept frames (uint32), each
    one's body depths (float16), point counts (uint32) and points (float16 x y z depth; a point 16 m
    from the origin is placed to 1 cm, which its marker hides) as four columns, all x, then all y,
    z and depth (a third smaller compressed than point by point)."""
    shown = [k for k, f in enumerate(keep) if f % pose_file.contact_stride == 0][::step]
    recorded = [int(keep[k]) // pose_file.contact_stride for k in shown]
    points = [pose_file.contacts_of(j) for j in recorded]
    return dict(contact_frames=packed(np.array(shown, "<u4")), depth=packed(halves(pose_file.depth[recorded])),
                contact_counts=packed(np.array([len(p) for p in points], "<u4")),
                contacts=packed(halves(np.concatenate(points).reshape(-1, CONTACT_FLOATS).T)))


def unpacked_frames(encoded: dict) -> np.ndarray:
    return np.frombuffer(gzip.decompress(base64.b64decode(encoded["contact_frames"])), "<u4")


def embedded_bytes(encoded: dict) -> int:
    return sum(len(v) for k, v in encoded.items() if k in ("times", "origin", "poses", "contact_frames", "depth",
                                                             "contact_counts", "contacts"))


def frames_every(count: int, step: int) -> np.ndarray:
    keep = list(range(0, count, step))
    if keep[-1] != count - 1:
        keep.append(count - 1)
    return np.array(keep)


def shown_rows(rows) -> list:
    """One row per engine at the scene's own step with a pose file: its default variant."""
    chosen = {}
    for _, r in rows.iterrows():
        engine = r["engine"]
        preferred = SHOWN_VARIANTS.get(engine, [])
        rank = preferred.index(r["variant"]) if r["variant"] in preferred else len(preferred)
        if engine not in chosen or rank < chosen[engine][0]:
            chosen[engine] = (rank, r)
    return [r for _, r in chosen.values()]


def scene_shapes(scene: dict) -> dict:
    """What the viewer draws besides the bodies' poses: static bodies, each dynamic body's shape,
    the particles' planes and attractors, springs and their world anchors."""
    bodies = scene.get("bodies", [])
    shapes, static = {}, []
    for i, b in enumerate(bodies):
        shape = b.get("shape", {"type": "box", "half_extents": [0.5, 0.5, 0.5]})
        if b.get("mass", 1.0) == 0:
            static.append(dict(shape=shape, position=b.get("position", [0, 0, 0]),
                               orientation=b.get("orientation", [1, 0, 0, 0])))
        else:
            shapes[str(i)] = shape
    springs = [dict(body_a=s.get("body_a", 0), local_point_a=s.get("local_point_a", [0, 0, 0]),
                    body_b=s.get("body_b", -1), point_b=s.get("point_b", [0, 0, 0]))
               for s in scene.get("springs", [])]
    particles = scene.get("particles")
    return dict(name=scene.get("name", ""), planar=bool(scene.get("planar", False)), static=static, shapes=shapes,
                springs=springs, anchors=[s["point_b"] for s in springs if s["body_b"] < 0],
                particles=dict(planes=particles.get("planes", []), attractors=particles.get("attractors", []))
                if particles else None)


def replay_for(folder: Path, name: str, rows, meta: dict, budget: int) -> tuple[dict | None, str, int]:
    """The viewer's poses for one scenario within min(SCENE_BYTES, budget) compressed bytes: dict(
    data=what the viewer reads, runs, keeps=each run's kept frames, step, size), or (None, why not)."""
    info = meta.get("scenarios", {}).get(name, {})
    scene_files = info.get("scene_file") or {}
    own_dt = info.get("dt")
    scene_file = None
    for dt, path in scene_files.items():
        if own_dt is None or abs(float(dt) - own_dt) <= 1e-6 * own_dt:
            scene_file = folder / path
    if scene_file is None or not scene_file.is_file():
        return None, "its scene file is not in scenes/"
    runs = []
    for r in shown_rows(rows):
        trajectory = r.get("trajectory")
        if not isinstance(trajectory, str):
            continue
        pose_file = folder / "poses" / (Path(trajectory).stem + ".bin")
        if not pose_file.is_file():
            continue
        recorded = read_pose_file(pose_file)
        if len(recorded.times) == 0:
            continue
        ended = ""
        if r["status"] != "ok":
            ended = f"{r['status']}: {r['message']}" if isinstance(r.get("message"), str) else r["status"]
        runs.append(dict(label=f"{r['engine']}/{r['variant']}", engine=r["engine"], status=r["status"], ended=ended,
                         bodies=[int(i) for i in recorded.index], recorded=recorded))
    if not runs:
        return None, "no engine left a pose file for it (poses/)"
    cap = min(SCENE_BYTES, budget)
    longest = max(len(run["recorded"].times) for run in runs)
    # one recorded frame in 2, 4, … until every engine's fits
    step = 1
    while True:
        keeps = [frames_every(len(run["recorded"].times), step) for run in runs]
        encoded = [encode_run(run["recorded"], keep) for run, keep in zip(runs, keeps)]
        size = sum(embedded_bytes(e) for e in encoded)
        if size <= cap or step >= longest:
            break
        step *= 2
    if size > cap:
        return None, f"even two frames per engine take {size:,} bytes, over the {cap:,} left to it"
    data = scene_shapes(json.loads(scene_file.read_text()))
    data["runs"] = [dict(label=run["label"], engine=run["engine"], status=run["status"], ended=run["ended"],
                         bodies=run["bodies"], **e) for run, e in zip(runs, encoded)]
    frames_per_s = [(len(run["recorded"].times) - 1) / max(1e-9, float(run["recorded"].times[-1])) / step
                    for run in runs]
    note = (f"about {min(frames_per_s):.3g} frames per simulated second"
            + (f" (one recorded frame in {step}, to fit the poses in {cap:,} bytes)" if step > 1 else ""))
    return dict(data=data, runs=runs, keeps=keeps, size=size), note


def add_contacts(scene: dict, room: int) -> tuple[int, str]:
    """Adds to a scene's viewer data the contacts of one kept frame in 1, 2, 4, … that has them,
    within room compressed bytes, or none; their bytes and a note."""
    runs, keeps = scene["runs"], scene["keeps"]
    if not any(run["recorded"].contact_stride for run in runs):
        return 0, ""
    longest = max(len(keep) for keep in keeps)
    step = 1
    while True:
        contacts = [encode_contacts(run["recorded"], keep, step) if run["recorded"].contact_stride else {}
                    for run, keep in zip(runs, keeps)]
        size = sum(embedded_bytes(c) for c in contacts)
        if size <= room or step >= longest:
            break
        step *= 2
    if size > room:
        return 0, f"; no contacts: {size:,} bytes for the fewest, {max(room, 0):,} left"
    for shown, c in zip(scene["data"]["runs"], contacts):
        shown.update(c)
    per_s = min(len(unpacked_frames(c)) / max(1e-9, float(run["recorded"].times[-1]))
                for run, c in zip(runs, contacts) if c)
    return size, f"; contacts and penetration at about {per_s:.2g} frames per simulated second"


def replays(folder: Path, results, meta: dict) -> dict:
    """Per scenario name: dict(json=the viewer's data as text, bytes=its compressed bytes,
    note=what it holds), or dict(json=None, note=why it has no viewer), for the scenes
    REPLAY_SCENES names. PAGE_BYTES counts compressed pose bytes, as SCENE_BYTES does; the contacts
    have budgets of their own, CONTACT_SCENE_BYTES and CONTACT_PAGE_BYTES, filled scene by scene in
    the same order once every scene's poses are placed."""
    out, scenes, budget = {}, {}, PAGE_BYTES
    present = set(results["scenario"])
    for name in REPLAY_SCENES:
        if name not in present:
            continue
        rows = results[results["scenario"] == name]
        own = meta.get("scenarios", {}).get(name, {}).get("dt")
        if own is not None:
            rows = rows[(rows["dt"] - own).abs() <= 1e-6 * own]
        if budget <= 0:
            out[name] = dict(json=None, bytes=0, note=f"not embedded: the page's replays reached {PAGE_BYTES:,} bytes")
            continue
        scene, note = replay_for(folder, name, rows, meta, budget)
        if scene is None:
            out[name] = dict(json=None, bytes=0, note=f"no replay: {note}")
            continue
        budget -= scene["size"]
        scenes[name] = (scene, note)
    contact_budget = CONTACT_PAGE_BYTES
    for name, (scene, note) in scenes.items():
        extra, contact_note = add_contacts(scene, min(CONTACT_SCENE_BYTES, contact_budget))
        contact_budget -= extra
        size = scene["size"] + extra
        text = json.dumps(scene["data"], separators=(",", ":"), allow_nan=False)
        # inside <script type="application/json">: no "</" may end the block early
        out[name] = dict(json=text.replace("</", "<\\/"), bytes=size,
                         note=f"{len(scene['runs'])} engines, {size:,} bytes embedded, {note}{contact_note}")
    return {name: out[name] for name in REPLAY_SCENES if name in out}


def viewer_script() -> str | None:
    """The bundled viewer (three.js and reports/viewer/src), or None when it is not built."""
    return VIEWER_JS.read_text(encoding="utf-8") if VIEWER_JS.is_file() else None
