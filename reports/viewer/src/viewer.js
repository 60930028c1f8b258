// physbench's replay viewer: each engine's recorded run of one scene, side by side in a grid of
// viewports drawn by one WebGL renderer, on one clock and one orbiting camera. The report builder
// (reports/build_report.py) embeds, per scene, a JSON block with the scene's shapes and each
// engine's frames; docs/viewer.md describes the data. three.js does all the drawing.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const BACKGROUND = 0xf4f6f8;
// a unit box's twelve edges as pairs of corners (±1 along each axis)
const BOX_EDGES = (() => {
  const edges = [];
  for (const axis of [0, 1, 2])
    for (const a of [-1, 1])
      for (const b of [-1, 1]) {
        const from = [0, 0, 0], to = [0, 0, 0];
        const [u, v] = [0, 1, 2].filter((k) => k !== axis);
        from[axis] = -1; to[axis] = 1;
        from[u] = to[u] = a; from[v] = to[v] = b;
        edges.push([from, to]);
      }
  return edges;
})();
const ENGINE_HUES = [0.58, 0.08, 0.33, 0.78, 0.0, 0.14, 0.5, 0.9];
const PALETTE_STOPS = [[0.19, 0.33, 0.72], [0.25, 0.72, 0.65], [0.95, 0.85, 0.3], [0.84, 0.19, 0.15]];
// the penetration scale's least top (m): a stack's sub-millimetre resting overlap is not painted red
const DEPTH_SCALE_FLOOR = 1e-3;
// contact markers, in pixels: a dark ring under a dot coloured by depth, seen on any body's colour
const CONTACT_DOT = 6, CONTACT_RING = 9;

// ---- data: base64 → gzip → float16 (positions as offsets from frame 0) ----------------------

function bytesOf(base64) {
  const text = atob(base64);
  const bytes = new Uint8Array(text.length);
  for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
  return bytes;
}

async function gunzip(bytes) {
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('gzip'));
  return new Uint8Array(await new Response(stream).arrayBuffer());
}

function halfToFloat(h) {
  const sign = h & 0x8000 ? -1 : 1;
  const exponent = (h >> 10) & 0x1f;
  const fraction = h & 0x3ff;
  if (exponent === 0) return sign * fraction * 2 ** -24;
  if (exponent === 31) return fraction ? NaN : sign * Infinity;
  return sign * (1 + fraction / 1024) * 2 ** (exponent - 15);
}

async function decodeHalves(base64) {
  const raw = await gunzip(bytesOf(base64));
  const halves = new Uint16Array(raw.buffer, raw.byteOffset, raw.byteLength / 2);
  const floats = new Float32Array(halves.length);
  for (let i = 0; i < halves.length; i++) floats[i] = halfToFloat(halves[i]);
  return floats;
}

// one engine's run: times, per frame and body [px py pz qx qy qz qw speed]; a contact scene's
// also, at its contact frames (contact_frames: which frames), each body's deepest penetration
// (depth, [contact frame][body]) and the contact points as four columns (all x, then all y, z and
// depth), contactStart[j] the first of contact frame j's; contactIndexOf[frame] is the contact
// frame at or before a frame
async function decodeRun(run) {
  const bodies = run.bodies.length;
  const frames = run.frames;
  const times = new Float32Array((await gunzip(bytesOf(run.times))).buffer);
  const origin = new Float32Array((await gunzip(bytesOf(run.origin))).buffer);
  const poses = await decodeHalves(run.poses);
  for (let f = 0; f < frames; f++)
    for (let b = 0; b < bodies; b++)
      for (let k = 0; k < 3; k++) poses[(f * bodies + b) * 8 + k] += origin[b * 3 + k];
  const decoded = { ...run, times, poses, depth: null, contacts: null };
  if (run.contacts) {
    const shown = new Uint32Array((await gunzip(bytesOf(run.contact_frames))).buffer);
    const counts = new Uint32Array((await gunzip(bytesOf(run.contact_counts))).buffer);
    decoded.depth = await decodeHalves(run.depth);
    decoded.contacts = await decodeHalves(run.contacts);
    decoded.contactStart = new Uint32Array(counts.length + 1);
    counts.forEach((n, j) => { decoded.contactStart[j + 1] = decoded.contactStart[j] + n; });
    decoded.contactIndexOf = new Int32Array(frames);
    for (let f = 0, j = 0; f < frames; f++) {
      while (j + 1 < shown.length && shown[j + 1] <= f) j++;
      decoded.contactIndexOf[f] = j;
    }
  }
  return decoded;
}

// ---- colours ---------------------------------------------------------------------------------

function paletteColour(x, target) {
  const t = Math.min(1, Math.max(0, x)) * (PALETTE_STOPS.length - 1);
  const i = Math.min(PALETTE_STOPS.length - 2, Math.floor(t));
  const a = PALETTE_STOPS[i], b = PALETTE_STOPS[i + 1], u = t - i;
  return target.setRGB(a[0] + (b[0] - a[0]) * u, a[1] + (b[1] - a[1]) * u, a[2] + (b[2] - a[2]) * u);
}

function engineColour(index, target) {
  return target.setHSL(ENGINE_HUES[index % ENGINE_HUES.length], 0.6, 0.5);
}

function bodyColour(index, target) {
  return target.setHSL((index * 0.618034) % 1, 0.55, 0.55);
}

// ---- the scene's static parts, drawn alike in every viewport ---------------------------------

function quaternion(q) {
  // scene files write [w, x, y, z]
  return q ? new THREE.Quaternion(q[1], q[2], q[3], q[0]) : new THREE.Quaternion();
}

function vector(v) {
  return v ? new THREE.Vector3(v[0], v[1], v[2]) : new THREE.Vector3();
}

function planeMesh(point, rotation, size, colour, opacity) {
  const geometry = new THREE.PlaneGeometry(size, size);
  geometry.rotateX(-Math.PI / 2);  // local y = 0 surface
  const material = new THREE.MeshLambertMaterial({
    color: colour, side: THREE.DoubleSide, transparent: opacity < 1, opacity, depthWrite: opacity >= 1,
  });
  const mesh = new THREE.Mesh(geometry, material);
  mesh.position.copy(point);
  mesh.quaternion.copy(rotation);
  const grid = new THREE.GridHelper(size, Math.round(size), 0xb0b8c0, 0xd0d6dc);
  grid.position.y = 0.002;
  mesh.add(grid);
  return mesh;
}

function staticParts(data, extent) {
  const group = new THREE.Group();
  const planeSize = Math.max(10, Math.ceil(extent * 3));
  for (const body of data.static) {
    const rotation = quaternion(body.orientation);
    const position = vector(body.position);
    if (body.shape.type === 'plane') {
      group.add(planeMesh(position, rotation, planeSize, 0xe3e7eb, 1));
    } else if (body.shape.type === 'box') {
      const h = body.shape.half_extents;
      const mesh = new THREE.Mesh(new THREE.BoxGeometry(2 * h[0], 2 * h[1], 2 * h[2]),
        new THREE.MeshLambertMaterial({ color: 0x9aa3ad, transparent: true, opacity: 0.45 }));
      mesh.position.copy(position);
      mesh.quaternion.copy(rotation);
      group.add(mesh);
    } else if (body.shape.type === 'sphere') {
      const mesh = new THREE.Mesh(new THREE.SphereGeometry(body.shape.radius, 24, 16),
        new THREE.MeshLambertMaterial({ color: 0x9aa3ad }));
      mesh.position.copy(position);
      group.add(mesh);
    }
  }
  const particles = data.particles;
  if (particles) {
    for (const plane of particles.planes || []) {
      const normal = vector(plane.normal).normalize();
      const rotation = new THREE.Quaternion().setFromUnitVectors(new THREE.Vector3(0, 1, 0), normal);
      group.add(planeMesh(vector(plane.point), rotation, planeSize, 0xc9d3dd, 0.5));
    }
    for (const a of particles.attractors || []) {
      const mesh = new THREE.Mesh(new THREE.SphereGeometry(0.12, 16, 12),
        new THREE.MeshBasicMaterial({ color: a.strength >= 0 ? 0x2b7a3d : 0xb3261e, wireframe: true }));
      mesh.position.copy(vector(a.position));
      group.add(mesh);
    }
  }
  for (const anchor of data.anchors || []) {
    const mesh = new THREE.Mesh(new THREE.SphereGeometry(0.06, 12, 8), new THREE.MeshBasicMaterial({ color: 0x333333 }));
    mesh.position.copy(vector(anchor));
    group.add(mesh);
  }
  return group;
}

// ---- one engine's viewport -------------------------------------------------------------------

class EngineView {
  constructor(data, run, index, extent) {
    this.run = run;
    this.index = index;
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(BACKGROUND);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8090a0, 1.4));
    const sun = new THREE.DirectionalLight(0xffffff, 1.5);
    sun.position.set(0.4, 1, 0.6);
    this.scene.add(sun);
    this.scene.add(staticParts(data, extent));

    // dynamic bodies by shape kind, each kind one instanced mesh; particles as points
    const shapes = data.shapes;  // scene body index → shape, for every probed rigid body
    this.boxes = []; this.spheres = []; this.points = [];
    run.bodies.forEach((body, column) => {
      const shape = shapes[String(body)];
      if (!shape) this.points.push(column);
      else if (shape.type === 'sphere') this.spheres.push([column, shape.radius]);
      else this.boxes.push([column, shape.half_extents]);
    });
    const material = new THREE.MeshLambertMaterial({ color: 0xffffff });
    if (this.boxes.length) {
      this.boxMesh = new THREE.InstancedMesh(new THREE.BoxGeometry(2, 2, 2), material, this.boxes.length);
      this.boxMesh.frustumCulled = false;
      this.scene.add(this.boxMesh);
      // each box's twelve edges, so boxes that touch (a stack) read as separate boxes
      const edges = new THREE.BufferGeometry();
      edges.setAttribute('position', new THREE.BufferAttribute(new Float32Array(this.boxes.length * 24 * 3), 3));
      this.edgeLines = new THREE.LineSegments(edges, new THREE.LineBasicMaterial({ color: 0x1d2630, transparent: true, opacity: 0.55 }));
      this.edgeLines.frustumCulled = false;
      this.scene.add(this.edgeLines);
    }
    if (this.spheres.length) {
      this.sphereMesh = new THREE.InstancedMesh(new THREE.SphereGeometry(1, 20, 14), material, this.spheres.length);
      this.sphereMesh.frustumCulled = false;
      this.scene.add(this.sphereMesh);
    }
    if (this.points.length) {
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(this.points.length * 3), 3));
      geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(this.points.length * 3), 3));
      this.pointCloud = new THREE.Points(geometry, new THREE.PointsMaterial({ size: 5, sizeAttenuation: false, vertexColors: true }));
      this.pointCloud.frustumCulled = false;
      this.scene.add(this.pointCloud);
    }
    // contact points: a dark ring under a dot coloured by depth, drawn over the bodies
    if (run.contacts) {
      let most = 0;
      for (let j = 1; j < run.contactStart.length; j++) most = Math.max(most, run.contactStart[j] - run.contactStart[j - 1]);
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(Math.max(1, most) * 3), 3));
      geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(Math.max(1, most) * 3), 3));
      const marker = (size, options) => {
        const points = new THREE.Points(geometry, new THREE.PointsMaterial({
          size, sizeAttenuation: false, depthTest: false, depthWrite: false, ...options,
        }));
        points.frustumCulled = false;
        points.visible = false;
        this.scene.add(points);
        return points;
      };
      this.contactRing = marker(CONTACT_RING, { color: 0x10161c });
      this.contactRing.renderOrder = 10;
      this.contactCloud = marker(CONTACT_DOT, { vertexColors: true });
      this.contactCloud.renderOrder = 11;
    }
    // springs: a line from the body's point to its anchor or the other body's point
    this.springs = (data.springs || []).map((s) => {
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(6), 3));
      const line = new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: 0x444444 }));
      line.frustumCulled = false;
      this.scene.add(line);
      return { ...s, line, columnA: run.bodies.indexOf(s.body_a), columnB: run.bodies.indexOf(s.body_b) };
    });
  }

  frameAt(time) {
    const times = this.run.times;
    let lo = 0, hi = times.length - 1;
    if (time >= times[hi]) return hi;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (times[mid] <= time) lo = mid; else hi = mid - 1;
    }
    return lo;
  }

  // the contact points shown at recorded frame `frame`: those of the contact frame at or before
  // it, coloured by depth; returns how many (null without contacts or when hidden)
  showContacts(frame, visible, depthScale) {
    if (!this.contactCloud) return null;
    this.contactCloud.visible = this.contactRing.visible = visible;
    if (!visible) return null;
    const run = this.run;
    const j = run.contactIndexOf[frame];
    const first = run.contactStart[j], count = run.contactStart[j + 1] - first;
    const geometry = this.contactCloud.geometry;
    const p = geometry.attributes.position, c = geometry.attributes.color;
    const colour = new THREE.Color();
    const column = run.contacts.length / 4;  // the points in all
    for (let i = 0; i < count; i++) {
      const o = first + i;
      p.setXYZ(i, run.contacts[o], run.contacts[column + o], run.contacts[2 * column + o]);
      paletteColour(run.contacts[3 * column + o] / depthScale, colour);
      c.setXYZ(i, colour.r, colour.g, colour.b);
    }
    geometry.setDrawRange(0, count);
    p.needsUpdate = true; c.needsUpdate = true;
    return count;
  }

  show(time, colouring, scales) {
    const frame = this.frameAt(time);
    const n = this.run.bodies.length;
    const poses = this.run.poses, times = this.run.times;
    const base = frame * n * 8;
    // between two recorded frames: positions and speeds linearly, orientations by slerp
    const next = Math.min(frame + 1, times.length - 1);
    const span = times[next] - times[frame];
    const alpha = span > 0 ? Math.min(1, Math.max(0, (time - times[frame]) / span)) : 0;
    const nextBase = next * n * 8;
    const otherPosition = new THREE.Vector3(), otherRotation = new THREE.Quaternion();
    const matrix = new THREE.Matrix4();
    const position = new THREE.Vector3(), rotation = new THREE.Quaternion(), scale = new THREE.Vector3();
    const colour = new THREE.Color();
    const hidden = new THREE.Matrix4().makeScale(0, 0, 0);
    const colourOf = (column) => {
      if (colouring === 'engine') return engineColour(this.index, colour);
      if (colouring === 'body') return bodyColour(this.run.bodies[column], colour);
      // the depth at the contact frame at or before, as the contact points shown (no depth: none
      // measured)
      if (colouring === 'penetration') {
        const depth = this.run.depth ? this.run.depth[this.run.contactIndexOf[frame] * n + column] : 0;
        return paletteColour(depth / scales.depth, colour);
      }
      const o = column * 8 + 7;
      return paletteColour((poses[base + o] * (1 - alpha) + poses[nextBase + o] * alpha) / scales.speed, colour);
    };
    const pose = (column) => {
      const o = base + column * 8, p = nextBase + column * 8;
      position.set(poses[o], poses[o + 1], poses[o + 2]);
      rotation.set(poses[o + 3], poses[o + 4], poses[o + 5], poses[o + 6]);
      if (alpha > 0) {
        position.lerp(otherPosition.set(poses[p], poses[p + 1], poses[p + 2]), alpha);
        otherRotation.set(poses[p + 3], poses[p + 4], poses[p + 5], poses[p + 6]);
        rotation.slerp(otherRotation, alpha);
      }
      return Number.isFinite(position.x + position.y + position.z + rotation.x + rotation.y + rotation.z + rotation.w);
    };
    const place = (mesh, list, scaleOf) => {
      list.forEach(([column, size], i) => {
        if (!pose(column)) { mesh.setMatrixAt(i, hidden); return; }
        rotation.normalize();
        scaleOf(size, scale);
        mesh.setMatrixAt(i, matrix.compose(position, rotation, scale));
        mesh.setColorAt(i, colourOf(column));
      });
      mesh.instanceMatrix.needsUpdate = true;
      if (mesh.instanceColor) mesh.instanceColor.needsUpdate = true;
    };
    if (this.boxMesh) {
      place(this.boxMesh, this.boxes, (h, s) => s.set(h[0], h[1], h[2]));
      const attr = this.edgeLines.geometry.attributes.position;
      const corner = new THREE.Vector3();
      this.boxes.forEach(([column, h], i) => {
        const finite = pose(column);
        rotation.normalize();
        for (let e = 0; e < 12; e++) {
          for (let end = 0; end < 2; end++) {
            const [cx, cy, cz] = BOX_EDGES[e][end];
            corner.set(cx * h[0], cy * h[1], cz * h[2]).applyQuaternion(rotation).add(position);
            if (!finite) corner.set(0, -1e9, 0);
            attr.setXYZ(i * 24 + e * 2 + end, corner.x, corner.y, corner.z);
          }
        }
      });
      attr.needsUpdate = true;
    }
    if (this.sphereMesh) place(this.sphereMesh, this.spheres, (r, s) => s.set(r, r, r));
    if (this.pointCloud) {
      const p = this.pointCloud.geometry.attributes.position, c = this.pointCloud.geometry.attributes.color;
      this.points.forEach((column, i) => {
        // a particle with no finite pose goes beyond the far plane
        if (pose(column)) p.setXYZ(i, position.x, position.y, position.z); else p.setXYZ(i, 0, -1e9, 0);
        colourOf(column);
        c.setXYZ(i, colour.r, colour.g, colour.b);
      });
      p.needsUpdate = true; c.needsUpdate = true;
    }
    for (const s of this.springs) {
      const attr = s.line.geometry.attributes.position;
      const end = (column, local) => {
        if (column < 0 || !pose(column)) return null;
        return vector(local).applyQuaternion(rotation).add(position);
      };
      const a = end(s.columnA, s.local_point_a);
      const b = s.body_b < 0 ? vector(s.point_b) : end(s.columnB, s.point_b);
      if (a && b) { attr.setXYZ(0, a.x, a.y, a.z); attr.setXYZ(1, b.x, b.y, b.z); }
      attr.needsUpdate = true;
    }
    return frame;
  }
}

// ---- one scene's replay: the grid, the clock and the controls --------------------------------

function reach(shape) {
  // the radius of a sphere around the shape's centre that holds it
  if (!shape) return 0.05;
  if (shape.type === 'sphere') return shape.radius;
  if (shape.type === 'box') return Math.hypot(...shape.half_extents);
  return 0;
}

function bounds(data, runs) {
  const box = new THREE.Box3();
  const first = runs[0];
  const sphere = new THREE.Sphere();
  for (let b = 0; b < first.bodies.length; b++) {
    const o = b * 8;
    const p = new THREE.Vector3(first.poses[o], first.poses[o + 1], first.poses[o + 2]);
    if (!Number.isFinite(p.x + p.y + p.z)) continue;
    sphere.set(p, reach(data.shapes[String(first.bodies[b])]));
    box.union(sphere.getBoundingBox(new THREE.Box3()));
  }
  for (const body of data.static) {
    if (body.shape.type === 'plane') continue;
    sphere.set(vector(body.position), reach(body.shape));
    box.union(sphere.getBoundingBox(new THREE.Box3()));
  }
  for (const a of (data.particles && data.particles.attractors) || []) box.expandByPoint(vector(a.position));
  for (const anchor of data.anchors || []) box.expandByPoint(vector(anchor));
  if (box.isEmpty()) box.set(new THREE.Vector3(-1, 0, -1), new THREE.Vector3(1, 1, 1));
  box.expandByScalar(0.25);
  return box;
}

// the 99th percentile of the finite values at `offset` in records of recordLength floats, over
// several arrays (about 20,000 records of each), or null when there are none
function percentile99(arrays, offset, recordLength) {
  const values = [];
  for (const a of arrays) {
    const step = recordLength * Math.max(1, Math.floor(a.length / recordLength / 20000));
    for (let i = offset; i < a.length; i += step) if (Number.isFinite(a[i])) values.push(a[i]);
  }
  values.sort((x, y) => x - y);
  return values.length ? values[Math.floor(0.99 * (values.length - 1))] : null;
}

class Replay {
  constructor(root, data, runs) {
    this.root = root;
    this.data = data;
    this.runs = runs;
    this.time = 0;
    this.playing = false;
    this.speed = 1;
    this.colouring = 'speed';
    this.duration = Math.max(1e-6, ...runs.map((r) => r.times[r.times.length - 1]));
    // the colour scale: the 99th percentile of every engine's speeds, so one runaway body does
    // not wash out the rest
    this.speedScale = Math.max(1e-3, percentile99(runs.map((r) => r.poses), 7, 8) ?? 1);
    // the penetration scale likewise: every engine's bodies' depths, 99th percentile, at least
    // DEPTH_SCALE_FLOOR; contact points share it
    this.hasDepth = runs.some((r) => r.depth);
    this.hasContacts = runs.some((r) => r.contacts);
    this.showContacts = false;
    this.depthScale = Math.max(DEPTH_SCALE_FLOOR, percentile99(runs.filter((r) => r.depth).map((r) => r.depth), 0, 1) ?? 0);

    const box = bounds(data, runs);
    const size = box.getSize(new THREE.Vector3());
    const extent = Math.max(size.x, size.y, size.z);
    this.views = runs.map((run, i) => new EngineView(data, run, i, extent));

    this.columns = Math.min(runs.length, runs.length === 4 ? 2 : 3);
    this.rows = Math.ceil(runs.length / this.columns);
    this.buildControls();
    const width = Math.max(320, root.clientWidth || 960);
    const cellHeight = Math.round(Math.min(360, (width / this.columns) * 0.75));
    this.width = width;
    this.height = cellHeight * this.rows;

    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(1);
    this.renderer.setSize(this.width, this.height);
    this.renderer.setScissorTest(true);
    this.canvas = this.renderer.domElement;
    this.canvas.className = 'replay-canvas';
    this.stage.appendChild(this.canvas);
    this.labels = runs.map((run, i) => {
      const label = document.createElement('div');
      label.className = 'replay-label';
      label.style.left = `${(i % this.columns) * (this.width / this.columns) + 6}px`;
      label.style.top = `${Math.floor(i / this.columns) * cellHeight + 4}px`;
      label.style.color = `#${engineColour(i, new THREE.Color()).offsetHSL(0, 0, -0.15).getHexString()}`;
      this.stage.appendChild(label);
      return label;
    });

    const centre = box.getCenter(new THREE.Vector3());
    this.camera = new THREE.PerspectiveCamera(40, this.width / this.columns / cellHeight, 0.05, extent * 50 + 100);
    const distance = extent * 1.6 + 1;
    const direction = data.planar ? new THREE.Vector3(0.45, 0.35, 1) : new THREE.Vector3(0.8, 0.55, 1);
    this.camera.position.copy(centre).addScaledVector(direction.normalize(), distance);
    this.controls = new OrbitControls(this.camera, this.canvas);
    this.controls.target.copy(centre);
    this.controls.update();
    this.controls.addEventListener('change', () => this.render());
    this.setTime(0);
  }

  buildControls() {
    const bar = document.createElement('div');
    bar.className = 'replay-controls';
    const button = (text, onClick) => {
      const b = document.createElement('button');
      b.type = 'button';
      b.textContent = text;
      b.addEventListener('click', onClick);
      bar.appendChild(b);
      return b;
    };
    this.playButton = button('▶ play', () => this.toggle());
    this.slider = document.createElement('input');
    Object.assign(this.slider, { type: 'range', min: '0', max: '1000', step: '1', value: '0' });
    this.slider.className = 'replay-slider';
    this.slider.addEventListener('input', () => this.setTime((this.slider.value / 1000) * this.duration));
    bar.appendChild(this.slider);
    this.clock = document.createElement('span');
    this.clock.className = 'replay-clock';
    bar.appendChild(this.clock);
    const select = (label, options, onChange) => {
      const l = document.createElement('label');
      l.textContent = `${label} `;
      const s = document.createElement('select');
      for (const [value, text] of options) s.add(new Option(text, value));
      s.addEventListener('change', () => onChange(s.value));
      l.appendChild(s);
      bar.appendChild(l);
      return s;
    };
    this.speedSelect = select('speed', [['0.25', '¼×'], ['0.5', '½×'], ['1', '1×'], ['2', '2×'], ['4', '4×']],
      (v) => { this.speed = Number(v); });
    this.speedSelect.value = '1';
    const colourings = [['speed', 'speed'], ['body', 'body'], ['engine', 'engine']];
    if (this.hasDepth) colourings.splice(1, 0, ['penetration', 'penetration']);
    this.colourSelect = select('colour by', colourings, (v) => { this.colouring = v; this.setTime(this.time); });
    // a scene whose bodies never move their centres (a box spinning in place) is coloured by body
    if (this.speedScale < 1e-2) this.colouring = 'body';
    this.colourSelect.value = this.colouring;
    if (this.hasContacts) {
      const l = document.createElement('label');
      this.contactsBox = document.createElement('input');
      this.contactsBox.type = 'checkbox';
      this.contactsBox.addEventListener('change', () => { this.showContacts = this.contactsBox.checked; this.setTime(this.time); });
      l.append(this.contactsBox, ' contact points');
      bar.appendChild(l);
    }
    this.legend = document.createElement('span');
    this.legend.className = 'replay-legend';
    bar.appendChild(this.legend);
    this.root.appendChild(bar);
    this.stage = document.createElement('div');
    this.stage.className = 'replay-stage';
    this.root.appendChild(this.stage);
  }

  toggle() {
    this.playing = !this.playing;
    this.playButton.textContent = this.playing ? '❚❚ pause' : '▶ play';
    if (!this.playing) return;
    if (this.time >= this.duration) this.setTime(0);
    let last = performance.now();
    const tick = (now) => {
      if (!this.playing) return;
      const next = this.time + ((now - last) / 1000) * this.speed;
      last = now;
      if (next >= this.duration) { this.setTime(this.duration); this.toggle(); return; }
      this.setTime(next);
      requestAnimationFrame(tick);
    };
    requestAnimationFrame(tick);
  }

  setTime(time) {
    this.time = Math.min(this.duration, Math.max(0, time));
    this.slider.value = String(Math.round((this.time / this.duration) * 1000) || 0);
    this.clock.textContent = `t = ${this.time.toFixed(2)} s of ${this.duration.toFixed(2)} s`;
    const depthLegend = `blue 0 → red ≥ ${(1000 * this.depthScale).toPrecision(2)} mm`;
    const legend = [];
    if (this.colouring === 'speed') legend.push(`blue 0 → red ≥ ${this.speedScale.toPrecision(2)} m/s`);
    if (this.colouring === 'penetration') legend.push(`each body's deepest overlap: ${depthLegend}`);
    if (this.showContacts) legend.push(`contact points by depth: ${depthLegend}`);
    this.legend.textContent = legend.join(' · ');
    const scales = { speed: this.speedScale, depth: this.depthScale };
    this.views.forEach((view, i) => {
      const frame = view.show(this.time, this.colouring, scales);
      const contacts = view.showContacts(frame, this.showContacts, this.depthScale);
      const run = view.run;
      const ended = run.ended && this.time > run.times[run.times.length - 1] ? ` — ${run.ended}` : '';
      const shown = contacts === null ? '' : `, ${contacts} contact point${contacts === 1 ? '' : 's'}`;
      this.labels[i].textContent = `${run.label} (frame ${frame + 1}/${run.frames}${shown})${ended}`;
    });
    this.render();
  }

  // viewport i in canvas pixels, origin at the top left
  viewport(i) {
    const w = Math.floor(this.width / this.columns), h = Math.floor(this.height / this.rows);
    return { x: (i % this.columns) * w, y: Math.floor(i / this.columns) * h, w, h };
  }

  render() {
    this.renderer.setScissor(0, 0, this.width, this.height);
    this.renderer.setClearColor(0xffffff);
    this.renderer.clear();
    this.views.forEach((view, i) => {
      const v = this.viewport(i);
      const y = this.height - v.y - v.h;  // WebGL counts rows from the bottom
      this.renderer.setViewport(v.x, y, v.w, v.h);
      this.renderer.setScissor(v.x, y, v.w, v.h);
      this.camera.aspect = v.w / v.h;
      this.camera.updateProjectionMatrix();
      this.renderer.render(view.scene, this.camera);
    });
  }
}

// ---- start every replay on the page ------------------------------------------------------------

async function start(root) {
  const source = document.getElementById(root.dataset.replay);
  const data = JSON.parse(source.textContent);
  const runs = await Promise.all(data.runs.map(decodeRun));
  return new Replay(root, data, runs);
}

// each replay starts (decodes its poses, makes its WebGL canvas) when it comes within two windows'
// height of the view, so a page of replays opens as fast as its first screen; the ready flag
// says the replays near the window at load have started, and window.physbenchStartReplays()
// starts every one (the browser test) and resolves to them all, in page order
const started = new Map();

function startOne(root) {
  if (!started.has(root)) {
    started.set(root, start(root).catch((error) => {
      root.textContent = `The replay could not start: ${error.message}`;
      console.error('replay', root.dataset.replay, error);
      return null;
    }));
  }
  return started.get(root);
}

function roots() {
  return [...document.querySelectorAll('.replay[data-replay]')];
}

async function startAll() {
  const replays = (await Promise.all(roots().map(startOne))).filter(Boolean);
  window.physbenchReplays = replays;
  return replays;
}

async function startNear() {
  window.physbenchStartReplays = startAll;
  const all = roots();
  if (!('IntersectionObserver' in window)) {
    await startAll();
  } else {
    const near = new IntersectionObserver((seen) => seen.forEach((e) => {
      if (e.isIntersecting) {
        near.unobserve(e.target);
        startOne(e.target);
      }
    }), { rootMargin: '200% 0px' });
    const reach = 3 * window.innerHeight;
    for (const root of all) {
      if (root.getBoundingClientRect().top < reach) startOne(root);
      else near.observe(root);
    }
    window.physbenchReplays = (await Promise.all([...started.values()])).filter(Boolean);
  }
  window.physbenchReplaysReady = true;
}

if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', startNear);
else startNear();
