#!/usr/bin/env python3
"""The converged reference of scenes without contacts: the rigid-body equations of motion
integrated by SciPy's DOP853 (an explicit Runge–Kutta of order 8 with step control), an integrator
no engine in the comparison uses, so no engine's own method is the yardstick.

Each body's state is its centre of mass x, velocity v, orientation q (unit quaternion, w x y z,
body to world) and angular momentum L about its centre (world): dx/dt = v, dv/dt = g + F/m,
dq/dt = ½ (0, ω) q with ω = R I⁻¹ Rᵀ L, dL/dt = τ. Forces are the scene's: gravity, and springs
(Hooke plus damping along the line between the attachment points, on both ends, as every adapter
models them). A scheduled impulse is applied at t = round(time / dt) · dt, between two integrations
(v += J / m, L += (p − x) × J). Contacts and particles are not modelled: such a scene is
`unsupported`.

It speaks the worker protocol (docs/worker-protocol.md): variants `dop853` (rtol 1e-12, the
reference) and `dop853-1e-13` (rtol 1e-13: the change from the first bounds the first's error).
    scipy_reference.py --scene S.json --variant dop853 --every N --out R.json
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np
import scipy
from scipy.integrate import solve_ivp

TOLERANCES = {"dop853": 1e-12, "dop853-1e-13": 1e-13}


def principal_inertia(shape: dict, mass: float) -> np.ndarray:
    """The scene format's mass properties (adapters/src/scene.cpp, principal_inertia)."""
    if shape["type"] == "sphere":
        return np.full(3, 0.4 * mass * shape["radius"] ** 2)
    h = np.asarray(shape["half_extents"], float)
    return mass / 3.0 * np.array([h[1] ** 2 + h[2] ** 2, h[0] ** 2 + h[2] ** 2, h[0] ** 2 + h[1] ** 2])


def rotation(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def rotations(q: np.ndarray) -> np.ndarray:
    """rotation() of each row of q (n × 4), as n × 3 × 3."""
    q = q / np.linalg.norm(q, axis=1)[:, None]
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=1),
                     np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=1),
                     np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=1)],
                    axis=1)


class Model:
    """The scene's free bodies and springs as one first-order system, 13 numbers a dynamic body."""

    def __init__(self, scene: dict):
        self.gravity = np.asarray(scene["gravity"], float)
        self.bodies = scene["bodies"]
        self.dynamic = [i for i, b in enumerate(self.bodies) if b["mass"] > 0.0]
        self.slot = {body: k for k, body in enumerate(self.dynamic)}
        self.mass = {i: self.bodies[i]["mass"] for i in self.dynamic}
        self.inverse_inertia = {i: 1.0 / principal_inertia(self.bodies[i]["shape"], self.mass[i])
                                for i in self.dynamic}
        self.springs = scene.get("springs", [])
        # the right-hand side on arrays: every scene body a row (a static one at its pose, at rest)
        # and a last row for the world a spring may be anchored to
        count = len(self.bodies)
        self.rows = np.array(self.dynamic, dtype=int)
        self.masses = np.array([self.mass[i] for i in self.dynamic])
        self.inverse_inertias = np.array([self.inverse_inertia[i] for i in self.dynamic]).reshape(-1, 3)
        self.static_x = np.zeros((count + 1, 3))
        self.static_r = np.tile(np.eye(3), (count + 1, 1, 1))
        for i, b in enumerate(self.bodies):
            if b["mass"] <= 0.0:
                self.static_x[i] = b["position"]
                self.static_r[i] = rotation(np.asarray(b["orientation"], float))
        springs = self.springs
        self.spring_a = np.array([sp["body_a"] for sp in springs], dtype=int)
        self.spring_b = np.array([count if sp["body_b"] < 0 else sp["body_b"] for sp in springs], dtype=int)
        self.local_a = np.array([sp["local_point_a"] for sp in springs], float).reshape(-1, 3)
        self.local_b = np.array([sp["point_b"] for sp in springs], float).reshape(-1, 3)
        self.stiffness = np.array([sp["stiffness"] for sp in springs], float)
        self.damping = np.array([sp["damping"] for sp in springs], float)
        self.rest = np.array([sp["rest_length"] for sp in springs], float)

    def initial(self) -> np.ndarray:
        y = np.zeros(13 * len(self.dynamic))
        for i in self.dynamic:
            b, s = self.bodies[i], 13 * self.slot[i]
            q = np.asarray(b["orientation"], float)
            r = rotation(q)
            inertia = 1.0 / self.inverse_inertia[i]
            y[s:s + 3] = b["position"]
            y[s + 3:s + 6] = b["linear_velocity"]
            y[s + 6:s + 10] = q
            y[s + 10:s + 13] = r @ (inertia * (r.T @ np.asarray(b["angular_velocity"], float)))
        return y

    def pose(self, y: np.ndarray, body: int):
        """x, v, R, ω of a body (a static one at its scene pose, at rest)."""
        if body not in self.slot:
            b = self.bodies[body]
            return (np.asarray(b["position"], float), np.zeros(3),
                    rotation(np.asarray(b["orientation"], float)), np.zeros(3))
        s = 13 * self.slot[body]
        r = rotation(y[s + 6:s + 10])
        omega = r @ (self.inverse_inertia[body] * (r.T @ y[s + 10:s + 13]))
        return y[s:s + 3], y[s + 3:s + 6], r, omega

    def rates(self, _t: float, y: np.ndarray) -> np.ndarray:
        state = y.reshape(-1, 13)
        x, v, q, momentum = state[:, 0:3], state[:, 3:6], state[:, 6:10], state[:, 10:13]
        r = rotations(q)
        omega = np.einsum("nij,nj->ni", r, self.inverse_inertias * np.einsum("nji,nj->ni", r, momentum))
        force = self.masses[:, None] * self.gravity
        torque = np.zeros_like(force)
        if len(self.spring_a):
            # every body's pose and velocity, the world's last
            all_x, all_r = self.static_x.copy(), self.static_r.copy()
            all_v, all_w = np.zeros_like(all_x), np.zeros_like(all_x)
            all_x[self.rows], all_r[self.rows], all_v[self.rows], all_w[self.rows] = x, r, v, omega
            a, b = self.spring_a, self.spring_b
            arm_a = np.einsum("kij,kj->ki", all_r[a], self.local_a)
            arm_b = np.einsum("kij,kj->ki", all_r[b], self.local_b)
            velocity_a = all_v[a] + np.cross(all_w[a], arm_a)
            velocity_b = all_v[b] + np.cross(all_w[b], arm_b)
            delta = (all_x[a] + arm_a) - (all_x[b] + arm_b)
            length = np.linalg.norm(delta, axis=1)
            pulls = length > 1e-12  # a spring of zero length has no direction: it pulls along nothing
            u = np.where(pulls[:, None], delta / np.where(pulls, length, 1.0)[:, None], 0.0)
            f = -(self.stiffness * (length - self.rest) +
                  self.damping * np.einsum("ki,ki->k", u, velocity_a - velocity_b))[:, None] * u
            all_f, all_t = np.zeros_like(all_x), np.zeros_like(all_x)
            np.add.at(all_f, a, f)
            np.add.at(all_f, b, -f)
            np.add.at(all_t, a, np.cross(arm_a, f))
            np.add.at(all_t, b, -np.cross(arm_b, f))
            force = force + all_f[self.rows]
            torque = torque + all_t[self.rows]
        # dq/dt = ½ (0, ω) ⊗ q
        w, qx, qy, qz = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
        ox, oy, oz = omega[:, 0], omega[:, 1], omega[:, 2]
        dq = 0.5 * np.stack([-ox * qx - oy * qy - oz * qz, ox * w + oy * qz - oz * qy,
                             oy * w + oz * qx - ox * qz, oz * w + ox * qy - oy * qx], axis=1)
        return np.concatenate([v, force / self.masses[:, None], dq, torque], axis=1).ravel()

    def apply_impulse(self, y: np.ndarray, impulse: dict) -> None:
        body = impulse["body"]
        if body not in self.slot:
            return
        s = 13 * self.slot[body]
        j = np.asarray(impulse["impulse"], float)
        y[s + 3:s + 6] += j / self.mass[body]
        y[s + 10:s + 13] += np.cross(np.asarray(impulse["point"], float) - y[s:s + 3], j)

    def sample(self, y: np.ndarray, probed: list[int]) -> list[float]:
        row = []
        for body in probed:
            x, v, _, omega = self.pose(y, body)
            s = 13 * self.slot[body]
            q = y[s + 6:s + 10] / np.linalg.norm(y[s + 6:s + 10])
            row += [*x, *q, *v, *omega]
        return [float(n) for n in row]


def unsupported(scene: dict) -> str | None:
    if scene.get("particles"):
        return "the SciPy reference integrates rigid bodies: particle sets are not modelled"
    if scene.get("collisions", True) and len(scene["bodies"]) > 1:
        return "the SciPy reference integrates free bodies, springs and impulses: no contacts"
    return None


def run(scene: dict, rtol: float, every: int) -> dict:
    dt, duration = scene["dt"], scene["duration"]
    steps = max(1, round(duration / dt))
    model = Model(scene)
    probed = scene["probe"]["bodies"] or model.dynamic
    # the sample times, as the harness samples an engine: every `every` steps and after the last
    sample_steps = list(range(0, steps + 1, every))
    if sample_steps[-1] != steps:
        sample_steps.append(steps)
    impulses_at = {}
    for p in scene.get("impulses", []):
        impulses_at.setdefault(round(p["time"] / dt), []).append(p)
    y = model.initial()
    # the state at a sample time is before any impulse due at that step (the harness samples,
    # then applies the step's impulses, then steps): integrate from each impulse to the next
    start = time.perf_counter()
    samples = [(0, model.sample(y, probed))]
    bounds = sorted({k for k in impulses_at if 0 < k < steps} | {steps})
    done = 0
    for end in bounds:
        for p in impulses_at.get(done, []):
            model.apply_impulse(y, p)
        times = [k for k in sample_steps if done < k <= end]
        at = sorted(set(times) | {end})
        solution = solve_ivp(model.rates, (done * dt, end * dt), y, method="DOP853", rtol=rtol,
                             atol=rtol * 1e-3, t_eval=[k * dt for k in at])
        if not solution.success:
            raise RuntimeError(f"solve_ivp failed before t = {end * dt}: {solution.message}")
        for k, column in zip(at, solution.y.T):
            if k in times:
                samples.append((k, model.sample(column, probed)))
        y = solution.y[:, -1].copy()
        done = end
    elapsed = time.perf_counter() - start
    return {"status": "ok", "message": "",
            "engine_version": f"SciPy {scipy.__version__} solve_ivp DOP853, rtol {rtol:g}",
            "settings": [{"name": "integrator", "value": f"DOP853, rtol {rtol:g}, atol {rtol * 1e-3:g}",
                          "why": "a converged reference no compared engine computed"}],
            "steps": steps, "wall_seconds": [elapsed], "bodies": probed,
            "samples": [[s * dt] + row for s, row in samples]}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", required=True)
    parser.add_argument("--variant", required=True, choices=sorted(TOLERANCES))
    parser.add_argument("--out", required=True)
    parser.add_argument("--every", type=int, default=0)
    parser.add_argument("--engine", default="scipy")
    parser.add_argument("--budget", type=float, default=0.0)  # one run: a reference is not timed
    args = parser.parse_args()
    with open(args.scene, encoding="utf-8") as f:
        scene = json.load(f)
    every = args.every if args.every > 0 else max(1, round(scene["probe"]["interval"] / scene["dt"]))
    why = unsupported(scene)
    try:
        result = ({"status": "unsupported", "message": why, "samples": [], "steps": 0,
                   "wall_seconds": [], "bodies": [], "settings": [], "engine_version": ""}
                  if why else run(scene, TOLERANCES[args.variant], every))
    except Exception as e:  # an integration that failed is a result with its reason, not a crash
        result = {"status": "error", "message": f"{type(e).__name__}: {e}", "samples": [], "steps": 0,
                  "wall_seconds": [], "bodies": [], "settings": [], "engine_version": ""}
    partial = args.out + ".partial"
    with open(partial, "w", encoding="utf-8") as f:
        json.dump(result, f)
    os.replace(partial, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
