//! The worker side of the harness's worker protocol (docs/worker-protocol.md): read the command
//! line and the scene file, drive an engine through the scene, sample the probed bodies, time the
//! steps and write the result file. An engine binary supplies only `Engine` and `World`.

pub mod checks;

use serde_json::{json, Value};
use std::time::Instant;

/// a body as the scene describes it (docs/scene-format.md); y is up by convention only
#[derive(Clone, Debug)]
pub enum Shape {
    Box { half_extents: [f64; 3] },
    Sphere { radius: f64 },
    Plane, // the body's local y = 0 surface, solid below; static only
}

#[derive(Clone, Debug)]
pub struct Body {
    pub name: String,
    pub shape: Shape,
    pub mass: f64, // kg; 0 = static
    pub position: [f64; 3],
    pub orientation: [f64; 4], // w, x, y, z; body to world
    pub linear_velocity: [f64; 3],
    pub angular_velocity: [f64; 3], // world frame (rad/s)
    pub friction: f64,
    pub restitution: f64,
}

impl Body {
    /// principal moments of inertia of the solid shape (kg m²), about the body axes
    pub fn principal_inertia(&self) -> [f64; 3] {
        match self.shape {
            Shape::Box { half_extents: h } => {
                let (x, y, z) = (4.0 * h[0] * h[0], 4.0 * h[1] * h[1], 4.0 * h[2] * h[2]);
                [self.mass * (y + z) / 12.0, self.mass * (x + z) / 12.0, self.mass * (x + y) / 12.0]
            }
            Shape::Sphere { radius } => [0.4 * self.mass * radius * radius; 3],
            Shape::Plane => [0.0; 3],
        }
    }
}

#[derive(Clone, Debug)]
pub struct Spring {
    pub body_a: usize,
    pub local_point_a: [f64; 3],
    pub body_b: Option<usize>, // None: point_b is a world anchor
    pub point_b: [f64; 3],
    pub stiffness: f64,
    pub damping: f64,
    pub rest_length: f64,
}

#[derive(Clone, Debug)]
pub struct Impulse {
    pub step: i64, // applied before the step that starts here
    pub body: usize,
    pub impulse: [f64; 3],
    pub point: [f64; 3],
}

#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub gravity: [f64; 3],
    pub dt: f64,
    pub duration: f64,
    pub planar: bool,
    pub collisions: bool,
    pub bodies: Vec<Body>,
    pub springs: Vec<Spring>,
    pub impulses: Vec<Impulse>,
    pub has_particles: bool,
    pub probe_bodies: Vec<usize>,
    pub probe_interval: f64,
}

/// the scene's pair rule (docs/scene-format.md, "Contacts")
pub const RESTITUTION_THRESHOLD: f64 = 0.1; // m/s: slower impacts are inelastic

impl Scene {
    pub fn step_count(&self) -> i64 {
        (self.duration / self.dt).round() as i64
    }
    pub fn probe_every_steps(&self) -> i64 {
        ((self.probe_interval / self.dt).round() as i64).max(1)
    }
    pub fn has_contacts(&self) -> bool {
        self.collisions && self.bodies.len() > 1
    }
    /// Springs reach the engines as an external force held over the whole step. An engine that
    /// substeps would advance its positions through the step's substeps under that stale force
    /// (a mix of explicit and semi-implicit Euler: the conformance spring's energy doubled in
    /// 5 s); substeps serve only contacts, so a scene with springs and no contacts is stepped in
    /// one substep, which makes it the same semi-implicit Euler as the other peers' springs.
    pub fn springs_without_contacts(&self) -> bool {
        !self.springs.is_empty() && !self.has_contacts()
    }
    /// Some(reason) for a scene with particle sets: no worker maps them yet
    pub fn particles_unsupported(&self, worker: &str) -> Option<String> {
        self.has_particles.then(|| format!("particle sets are not mapped in the {worker} worker \
                                            yet (the shared particle driver is C++ only)"))
    }
    /// Some(reason) when an equal-iterations variant would repeat the default's row: on a
    /// scene without contacts iterations change nothing
    pub fn iterations_not_applicable(&self, variant: &str, why: &str) -> Option<String> {
        (variant == "iterations-10" && !self.has_contacts()).then(|| why.to_string())
    }
    /// every body shares one friction and one restitution
    pub fn one_material(&self) -> bool {
        self.bodies.windows(2).all(|w| {
            w[0].friction == w[1].friction && w[0].restitution == w[1].restitution
        })
    }
}

fn vec3(v: Option<&Value>, default: [f64; 3]) -> Result<[f64; 3], String> {
    match v {
        None => Ok(default),
        Some(a) => {
            let a = a.as_array().ok_or("expected an array of 3 numbers")?;
            if a.len() != 3 {
                return Err("expected 3 numbers".into());
            }
            let mut out = [0.0; 3];
            for (o, x) in out.iter_mut().zip(a) {
                *o = x.as_f64().ok_or("expected a number")?;
            }
            Ok(out)
        }
    }
}

fn number(v: Option<&Value>, default: f64) -> Result<f64, String> {
    match v {
        None => Ok(default),
        Some(x) => x.as_f64().ok_or_else(|| "expected a number".to_string()),
    }
}

/// reads a scene file as the harness writes it (it has already been validated there)
pub fn load_scene(path: &str) -> Result<Scene, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {path}: {e}"))?;
    let doc: Value = serde_json::from_str(&text).map_err(|e| format!("{path}: {e}"))?;
    let mut bodies = Vec::new();
    for b in doc["bodies"].as_array().ok_or("bodies missing")? {
        let shape = &b["shape"];
        let shape = match shape["type"].as_str() {
            Some("box") => Shape::Box { half_extents: vec3(shape.get("half_extents"), [0.0; 3])? },
            Some("sphere") => Shape::Sphere { radius: number(shape.get("radius"), 0.0)? },
            Some("plane") => Shape::Plane,
            other => return Err(format!("unknown shape {other:?}")),
        };
        let q = match b.get("orientation") {
            None => [1.0, 0.0, 0.0, 0.0],
            Some(a) => {
                let a = a.as_array().ok_or("orientation")?;
                [a[0].as_f64().unwrap_or(1.0), a[1].as_f64().unwrap_or(0.0),
                 a[2].as_f64().unwrap_or(0.0), a[3].as_f64().unwrap_or(0.0)]
            }
        };
        bodies.push(Body {
            name: b["name"].as_str().unwrap_or("").to_string(),
            shape,
            mass: number(b.get("mass"), 0.0)?,
            position: vec3(b.get("position"), [0.0; 3])?,
            orientation: q,
            linear_velocity: vec3(b.get("linear_velocity"), [0.0; 3])?,
            angular_velocity: vec3(b.get("angular_velocity"), [0.0; 3])?,
            friction: number(b.get("friction"), 0.5)?,
            restitution: number(b.get("restitution"), 0.0)?,
        });
    }
    let mut springs = Vec::new();
    for s in doc["springs"].as_array().into_iter().flatten() {
        let body_b = s["body_b"].as_i64().unwrap_or(-1);
        springs.push(Spring {
            body_a: s["body_a"].as_u64().ok_or("springs[].body_a")? as usize,
            local_point_a: vec3(s.get("local_point_a"), [0.0; 3])?,
            body_b: if body_b < 0 { None } else { Some(body_b as usize) },
            point_b: vec3(s.get("point_b"), [0.0; 3])?,
            stiffness: number(s.get("stiffness"), 0.0)?,
            damping: number(s.get("damping"), 0.0)?,
            rest_length: number(s.get("rest_length"), 0.0)?,
        });
    }
    let dt = number(doc.get("dt"), 0.0)?;
    let mut impulses = Vec::new();
    for p in doc["impulses"].as_array().into_iter().flatten() {
        impulses.push(Impulse {
            step: (number(p.get("time"), 0.0)? / dt).round() as i64,
            body: p["body"].as_u64().ok_or("impulses[].body")? as usize,
            impulse: vec3(p.get("impulse"), [0.0; 3])?,
            point: vec3(p.get("point"), [0.0; 3])?,
        });
    }
    impulses.sort_by_key(|p| p.step);
    let probe = &doc["probe"];
    let mut probe_bodies: Vec<usize> = probe["bodies"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|v| v.as_u64().map(|i| i as usize))
        .collect();
    if probe_bodies.is_empty() {
        probe_bodies = (0..bodies.len()).filter(|&i| bodies[i].mass > 0.0).collect();
    }
    Ok(Scene {
        name: doc["name"].as_str().unwrap_or("").to_string(),
        gravity: vec3(doc.get("gravity"), [0.0, -9.81, 0.0])?,
        dt,
        duration: number(doc.get("duration"), 0.0)?,
        planar: doc["planar"].as_bool().unwrap_or(false),
        collisions: doc["collisions"].as_bool().unwrap_or(true),
        bodies,
        springs,
        impulses,
        has_particles: doc.get("particles").map_or(false, |p| !p.is_null()),
        probe_bodies,
        probe_interval: number(probe.get("interval"), 1.0 / 60.0)?,
    })
}

/// a body's state as the protocol samples it: centre of mass (m), orientation w x y z (body to
/// world), linear velocity (m/s), angular velocity (rad/s), all in the world frame
#[derive(Clone, Copy, Debug, Default)]
pub struct State {
    pub position: [f64; 3],
    pub orientation: [f64; 4],
    pub linear_velocity: [f64; 3],
    pub angular_velocity: [f64; 3],
}

/// one engine's world, built from a scene
pub trait World {
    /// one fixed step of the scene's dt, with the forces added since the last step
    fn step(&mut self);
    fn state(&self, body: usize) -> State;
    /// an external force (N) at a world point (m), for the next step only
    fn add_force_at_point(&mut self, body: usize, force: [f64; 3], point: [f64; 3]);
    /// an instantaneous impulse (N s) at a world point (m)
    fn apply_impulse(&mut self, body: usize, impulse: [f64; 3], point: [f64; 3]);
    /// Some(reason) when the engine itself reports that it broke down (an explosion)
    fn failure(&self) -> Option<String> {
        None
    }
    /// Some(reason) when the engine reports that its answer is wrong without breaking down
    /// (a full contact buffer dropped contacts): the run is an `error`, never a result
    fn error(&self) -> Option<String> {
        None
    }
    /// the contact points the engine's solver held in the last step, by its own count; None for
    /// an engine or scene that does not count them (the result then carries no `contacts`)
    fn contact_points(&self) -> Option<usize> {
        None
    }
}

#[derive(Debug)]
pub struct Setting {
    pub name: String,
    pub value: String,
    pub why: String,
}

pub fn setting(name: &str, value: impl ToString, why: &str) -> Setting {
    Setting { name: name.into(), value: value.to_string(), why: why.into() }
}

/// a sweep's solver knobs (`--iterations N`, `--substeps N`); 0 leaves the variant's own
#[derive(Clone, Copy, Debug, Default)]
pub struct Knobs {
    pub iterations: usize,
    pub substeps: usize,
}

impl Knobs {
    pub fn any(&self) -> bool {
        self.iterations > 0 || self.substeps > 0
    }
}

pub trait Engine {
    fn name(&self) -> &'static str;
    fn version(&self) -> String;
    fn variants(&self) -> &'static [&'static str];
    /// every setting that differs from the engine's defaults, with the reason
    fn settings(&self, variant: &str) -> Vec<Setting>;
    /// Some(reason) when this engine cannot model the scene as it is
    fn unsupported(&self, scene: &Scene, variant: &str) -> Option<String>;
    /// Some(reason) when the variant would not differ from another here (no row is made)
    fn not_applicable(&self, _scene: &Scene, _variant: &str) -> Option<String> {
        None
    }
    /// a sweep's knobs on the engine's nearest native ones: the settings that says they changed,
    /// or why the engine has no such knob (the row is `unsupported`)
    fn tune(&self, _variant: &str, knobs: &Knobs) -> Result<Vec<Setting>, String> {
        if knobs.any() {
            Err(format!("{} maps no solver iterations or substeps", self.name()))
        } else {
            Ok(Vec::new())
        }
    }
    /// a world for the scene at the variant, with a sweep's knobs (tune() accepted them)
    fn create(&self, scene: &Scene, variant: &str, knobs: &Knobs)
        -> Result<Box<dyn World>, String>;
}

/// `Engine::tune` of an engine whose only solver knob is its substep count (Box2D v3 and Box3D: one
/// biased solve and one relax pass a substep): substeps go to `step_call`, iterations are refused
pub fn tune_substeps_only(engine: &str, step_call: &str, knobs: &Knobs)
    -> Result<Vec<Setting>, String> {
    if knobs.iterations > 0 {
        return Err(format!("{engine} has no iteration count: one solve and one relax pass a \
                            substep (sweep its substeps)"));
    }
    Ok(if knobs.substeps > 0 {
        vec![setting("subStepCount", knobs.substeps,
                     &format!("the sweep's substeps (--sweep-substeps), passed to {step_call}"))]
    } else {
        Vec::new()
    })
}

fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let (w, x, y, z) = (q[0], q[1], q[2], q[3]);
    // v + 2 w (u × v) + 2 u × (u × v), u = (x, y, z)
    let t = [2.0 * (y * v[2] - z * v[1]), 2.0 * (z * v[0] - x * v[2]), 2.0 * (x * v[1] - y * v[0])];
    [
        v[0] + w * t[0] + (y * t[2] - z * t[1]),
        v[1] + w * t[1] + (z * t[0] - x * t[2]),
        v[2] + w * t[2] + (x * t[1] - y * t[0]),
    ]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// the scene's springs as external forces from the state at the start of the step: the same
/// law and the same method as the harness's in-process peers (adapters/src/springs.cpp)
fn add_spring_forces(scene: &Scene, world: &mut dyn World) {
    for s in &scene.springs {
        let a = world.state(s.body_a);
        let point_a = add(a.position, rotate(a.orientation, s.local_point_a));
        let velocity_a = add(a.linear_velocity, cross(a.angular_velocity, sub(point_a, a.position)));
        let (point_b, velocity_b) = match s.body_b {
            None => (s.point_b, [0.0; 3]),
            Some(b) => {
                let b = world.state(b);
                let p = add(b.position, rotate(b.orientation, s.point_b));
                (p, add(b.linear_velocity, cross(b.angular_velocity, sub(p, b.position))))
            }
        };
        let delta = sub(point_a, point_b);
        let length = (delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2]).sqrt();
        // a spring of zero length has no direction: it pulls along nothing
        if length <= 1e-12 {
            continue;
        }
        let direction = [delta[0] / length, delta[1] / length, delta[2] / length];
        let rate = (0..3).map(|k| direction[k] * (velocity_a[k] - velocity_b[k])).sum::<f64>();
        let magnitude = -(s.stiffness * (length - s.rest_length) + s.damping * rate);
        let force = [magnitude * direction[0], magnitude * direction[1], magnitude * direction[2]];
        if scene.bodies[s.body_a].mass > 0.0 {
            world.add_force_at_point(s.body_a, force, point_a);
        }
        if let Some(b) = s.body_b {
            if scene.bodies[b].mass > 0.0 {
                world.add_force_at_point(b, [-force[0], -force[1], -force[2]], point_b);
            }
        }
    }
}

// a body farther than this from the origin has exploded (the harness's own limit)
const EXPLOSION_DISTANCE: f64 = 1e6;

fn sane(s: &State) -> bool {
    let all = s.position.iter().chain(&s.orientation).chain(&s.linear_velocity)
        .chain(&s.angular_velocity);
    let mut finite = true;
    for x in all {
        finite &= x.is_finite();
    }
    let r2: f64 = s.position.iter().map(|x| x * x).sum();
    finite && r2.sqrt() <= EXPLOSION_DISTANCE
}

struct Pass {
    stepping_seconds: f64,
    exploded: Option<String>,
    error: Option<String>,
    contact_points: f64, // summed over the steps that counted them
    contact_steps: i64,
    /// the steps taken when the run cap stopped the run; 0: it ran to the end
    capped_at: i64,
}

/// one run of the whole scene; only the steps (forces, impulses and the engine's step) are timed,
/// the sampling between chunks is not
/// the steps taken when the run cap stopped the run; 0: it ran to the end. With a cap (s, 0: none)
/// the run stops after that much stepping, at the step that reaches it
fn run_once(scene: &Scene, world: &mut dyn World, every: i64, keep: Option<&mut Vec<Value>>,
            cap: f64) -> Pass {
    let mut keep = keep;
    let mut pass = Pass { stepping_seconds: 0.0, exploded: None, error: None, contact_points: 0.0,
                          contact_steps: 0, capped_at: 0 };
    let sample = |world: &dyn World, time: f64| -> (Value, bool) {
        let mut row = vec![json!(time)];
        let mut ok = true;
        for &b in &scene.probe_bodies {
            let s = world.state(b);
            ok &= sane(&s);
            for x in s.position.iter().chain(&s.orientation).chain(&s.linear_velocity)
                .chain(&s.angular_velocity) {
                row.push(if x.is_finite() { json!(x) } else { Value::Null });
            }
        }
        (Value::Array(row), ok)
    };
    if let Some(k) = keep.as_deref_mut() {
        k.push(sample(world, 0.0).0);
    }
    let steps = scene.step_count();
    let mut next_impulse = 0;
    let mut done = 0;
    while done < steps {
        let chunk = every.min(steps - done);
        let start = Instant::now();
        let mut counting = 0.0; // seconds spent counting contacts, taken off the chunk's time
        let mut taken = chunk;
        let mut over = false;
        for i in 0..chunk {
            while next_impulse < scene.impulses.len() && scene.impulses[next_impulse].step == done + i {
                let p = &scene.impulses[next_impulse];
                world.apply_impulse(p.body, p.impulse, p.point);
                next_impulse += 1;
            }
            add_spring_forces(scene, world);
            world.step();
            // every step's count (a walk over the manifolds), its time not the step's
            let count_start = Instant::now();
            if let Some(points) = world.contact_points() {
                pass.contact_points += points as f64;
                pass.contact_steps += 1;
            }
            counting += count_start.elapsed().as_secs_f64();
            if cap > 0.0
                && pass.stepping_seconds + start.elapsed().as_secs_f64() - counting >= cap {
                taken = i + 1;
                over = true;
                break;
            }
        }
        pass.stepping_seconds += (start.elapsed().as_secs_f64() - counting).max(0.0);
        done += taken;
        let time = done as f64 * scene.dt;
        let (row, ok) = sample(world, time);
        if let Some(k) = keep.as_deref_mut() {
            k.push(row);
        }
        if let Some(reason) = world.error() {
            pass.error = Some(format!("{reason} (by t = {time} s)"));
            return pass;
        }
        if let Some(reason) = world.failure() {
            pass.exploded = Some(format!("{reason} (by t = {time} s)"));
            return pass;
        }
        if !ok {
            pass.exploded = Some(format!("non-finite or runaway state at t = {time} s"));
            return pass;
        }
        if over && done < steps {
            pass.capped_at = done;
            return pass;
        }
    }
    pass
}

pub struct Job {
    pub scene: String,
    pub variant: String,
    pub every: i64,
    pub budget: f64,
    pub out: String,
    pub knobs: Knobs,
    /// a timing round (--timing-only): no sampled run, timed repeats only, at least one
    pub timing_only: bool,
    /// --run-cap S: the sampled run stops after S s of stepping, a timeout (0: none)
    pub run_cap: f64,
}

fn positive(option: &str, value: &str) -> Result<usize, String> {
    match value.parse::<usize>() {
        Ok(n) if n > 0 => Ok(n),
        _ => Err(format!("{option}: a positive integer, not '{value}'")),
    }
}

fn parse_args(engine: &dyn Engine) -> Result<Job, String> {
    let mut job = Job { scene: String::new(), variant: String::new(), every: 0, budget: 0.3,
                        out: String::new(), knobs: Knobs::default(), timing_only: false,
                        run_cap: 0.0 };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < args.len() {
        if args[i] == "--timing-only" {
            job.timing_only = true;
            i += 1;
            continue;
        }
        let value = args.get(i + 1).cloned().ok_or(format!("{} needs a value", args[i]))?;
        match args[i].as_str() {
            "--scene" => job.scene = value,
            "--variant" => job.variant = value,
            "--engine" => {
                if value != engine.name() {
                    return Err(format!("this worker runs {}, not {value}", engine.name()));
                }
            }
            "--every" => job.every = value.parse().map_err(|_| "--every: an integer")?,
            "--budget" => job.budget = value.parse().map_err(|_| "--budget: a number")?,
            "--out" => job.out = value,
            "--run-cap" => job.run_cap = value.parse().map_err(|_| "--run-cap: a number")?,
            "--iterations" => job.knobs.iterations = positive("--iterations", &value)?,
            "--substeps" => job.knobs.substeps = positive("--substeps", &value)?,
            other => return Err(format!("unknown option {other}")),
        }
        i += 2;
    }
    if job.scene.is_empty() || job.variant.is_empty() || job.out.is_empty() {
        return Err("usage: --scene FILE --variant NAME --out RESULT.json [--every N] \
                    [--budget S] [--engine NAME] [--iterations N] [--substeps N] \
                    [--timing-only] [--run-cap S]".into());
    }
    Ok(job)
}

const MIN_TIMED_REPEATS: usize = 3;
/// at most this many a round, each on a world built afresh (untimed): as the harness's own
/// engines (adapters/include/physbench/simulate.h, max_timed_repeats)
const MAX_TIMED_REPEATS: usize = 10;

fn simulate(engine: &dyn Engine, job: &Job) -> Value {
    let mut doc = json!({
        "status": "ok", "message": "", "engine_version": engine.version(),
        "settings": engine.settings(&job.variant).iter()
            .map(|s| json!({"name": s.name, "value": s.value, "why": s.why}))
            .collect::<Vec<_>>(),
        "steps": 0, "wall_seconds": [], "bodies": [], "samples": [],
    });
    let fail = |mut doc: Value, status: &str, message: String| {
        doc["status"] = json!(status);
        doc["message"] = json!(message);
        doc
    };
    let scene = match load_scene(&job.scene) {
        Ok(s) => s,
        Err(e) => return fail(doc, "error", e),
    };
    doc["steps"] = json!(scene.step_count());
    doc["bodies"] = json!(scene.probe_bodies);
    if !engine.variants().contains(&job.variant.as_str()) {
        let message = format!("engine {} has no variant '{}'", engine.name(), job.variant);
        return fail(doc, "error", message);
    }
    if let Some(why) = engine.not_applicable(&scene, &job.variant) {
        return fail(doc, "not-applicable", why);
    }
    if let Some(why) = engine.unsupported(&scene, &job.variant) {
        return fail(doc, "unsupported", why);
    }
    // a sweep's knobs: the settings they changed join the table, or the engine has no such knob
    match engine.tune(&job.variant, &job.knobs) {
        Ok(tuned) => {
            if let Some(table) = doc["settings"].as_array_mut() {
                table.extend(tuned.iter()
                    .map(|s| json!({"name": s.name, "value": s.value, "why": s.why})));
            }
        }
        Err(why) => return fail(doc, "unsupported", why),
    }
    let every = if job.every > 0 { job.every } else { scene.probe_every_steps() };

    // first run: the trajectory, and a warm-up for the timed repeats (a timing round has neither)
    let mut samples = Vec::new();
    let mut wall = Vec::new();
    if !job.timing_only {
        let mut world = match engine.create(&scene, &job.variant, &job.knobs) {
            Ok(w) => w,
            Err(e) => return fail(doc, "error", e),
        };
        let pass = run_once(&scene, world.as_mut(), every, Some(&mut samples), job.run_cap);
        wall.push(pass.stepping_seconds);
        if pass.contact_steps > 0 {
            doc["contacts"] = json!({"points": pass.contact_points, "steps": pass.contact_steps});
        }
        doc["samples"] = Value::Array(std::mem::take(&mut samples));
        if let Some(why) = pass.error {
            doc["wall_seconds"] = json!(wall);
            return fail(doc, "error", why);
        }
        if let Some(why) = pass.exploded {
            doc["wall_seconds"] = json!(wall);
            return fail(doc, "exploded", why);
        }
        if pass.capped_at > 0 {
            // too slow to finish: its speed from the steps it took, no verdict on part of a run
            let why = format!("too slow: stopped at the run cap after {} of {} steps ({:.3} s of \
                               stepping, --run-cap {} s); its speed is from those steps",
                              pass.capped_at, scene.step_count(), pass.stepping_seconds, job.run_cap);
            doc["steps"] = json!(pass.capped_at);
            doc["wall_seconds"] = json!(wall);
            return fail(doc, "timeout", why);
        }
        if pass.stepping_seconds >= job.budget {
            doc["wall_seconds"] = json!(wall);
            return doc;
        }
        wall.clear();
    }
    // timed repeats, each on a freshly built world
    let mut measured = 0.0;
    let min_repeats = if job.timing_only { 1 } else { MIN_TIMED_REPEATS };
    while wall.len() < MAX_TIMED_REPEATS && (wall.len() < min_repeats || measured < job.budget)
    {
        let mut world = match engine.create(&scene, &job.variant, &job.knobs) {
            Ok(w) => w,
            Err(e) => return fail(doc, "error", e),
        };
        let pass = run_once(&scene, world.as_mut(), every, None, 0.0);
        if let Some(why) = pass.error {
            return fail(doc, "error", why);
        }
        wall.push(pass.stepping_seconds);
        measured += pass.stepping_seconds;
    }
    doc["wall_seconds"] = json!(wall);
    doc
}

/// the worker's main: exit code 0 whenever a result file (of any status) was written
pub fn main(engine: &dyn Engine) -> ! {
    let job = match parse_args(engine) {
        Ok(j) => j,
        Err(e) => {
            eprintln!("{}: {e}", engine.name());
            std::process::exit(2);
        }
    };
    let result = simulate(engine, &job);
    let partial = format!("{}.partial", job.out);
    if let Err(e) = std::fs::write(&partial, result.to_string()) {
        eprintln!("{}: cannot write {partial}: {e}", engine.name());
        std::process::exit(3);
    }
    if let Err(e) = std::fs::rename(&partial, &job.out) {
        eprintln!("{}: cannot write {}: {e}", engine.name(), job.out);
        std::process::exit(3);
    }
    std::process::exit(0);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> String {
        let path = std::env::temp_dir().join(format!("physbench-worker-{}-{name}", std::process::id()));
        std::fs::write(&path, text).unwrap();
        path.to_string_lossy().into_owned()
    }

    #[test]
    fn a_scene_file_reads_with_the_formats_defaults() {
        let path = write("scene.json", r#"{"name": "s", "dt": 0.01, "duration": 1.0,
            "bodies": [{"name": "g", "shape": {"type": "plane"}},
                       {"name": "b", "shape": {"type": "box", "half_extents": [1, 2, 3]},
                        "mass": 2, "position": [0, 1, 0]}],
            "impulses": [{"time": 0.5, "body": 1, "impulse": [0, 1, 0]},
                         {"time": 0.2, "body": 1, "impulse": [1, 0, 0]}]}"#);
        let scene = load_scene(&path).unwrap();
        assert_eq!(scene.gravity, [0.0, -9.81, 0.0]);
        assert!(scene.collisions && !scene.planar && !scene.has_particles);
        // friction 0.5 and restitution 0 when a body gives none (docs/scene-format.md)
        assert_eq!((scene.bodies[1].friction, scene.bodies[1].restitution), (0.5, 0.0));
        // the probe defaults to the dynamic bodies
        assert_eq!(scene.probe_bodies, vec![1]);
        // impulses in step order, at the step their time rounds to
        assert_eq!(scene.impulses.iter().map(|p| p.step).collect::<Vec<_>>(), vec![20, 50]);
        assert_eq!(scene.step_count(), 100);
        assert!(scene.has_contacts() && scene.one_material());
    }

    #[test]
    fn a_bad_scene_file_names_what_is_wrong() {
        let path = write("bad.json", r#"{"bodies": [{"shape": {"type": "cone"}}]}"#);
        assert!(load_scene(&path).unwrap_err().contains("cone"));
        assert!(load_scene("/no/such/file.json").unwrap_err().contains("/no/such/file.json"));
    }

    #[test]
    fn a_box_has_the_solid_boxs_inertia() {
        let b = Body { name: "b".into(), shape: Shape::Box { half_extents: [0.5, 1.0, 1.5] },
                       mass: 12.0, position: [0.0; 3], orientation: [1.0, 0.0, 0.0, 0.0],
                       linear_velocity: [0.0; 3], angular_velocity: [0.0; 3], friction: 0.5,
                       restitution: 0.0 };
        // m (b² + c²) / 12 with full sides 1, 2, 3
        assert_eq!(b.principal_inertia(), [13.0, 10.0, 5.0]);
    }

    #[test]
    fn rotate_turns_a_vector_by_the_quaternion() {
        let half = std::f64::consts::FRAC_PI_4; // a quarter turn about z
        let q = [half.cos(), 0.0, 0.0, half.sin()];
        let v = rotate(q, [1.0, 0.0, 0.0]);
        assert!((v[0]).abs() < 1e-12 && (v[1] - 1.0).abs() < 1e-12 && v[2].abs() < 1e-12);
    }
}
